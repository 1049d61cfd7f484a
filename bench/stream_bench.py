#!/usr/bin/env python3
"""The live streams (issue #40): frames per second and end-to-end latency through
GET …/stylizer/stream (MJPEG) at 960×540 and 1920×1080, the paper's forest scene, and through
the painting page's GET …/viewport/stream (the 64³ cloud orbited at 320², the page's size, and
480²; --viewport-sizes).

Starts `volstyle serve` on a free loopback port, opens the stream, then plays scene time as the
page's Play button does:
  - closed loop: the next change (PUT …/stylizer with a later time) goes out when the frame of
    the last one arrives: latency = PUT sent → its frame's last byte here; fps = frames / wall.
  - open loop: changes at 60 Hz regardless; the server renders only the newest revision each
    time, so fps is what it sustains and the skipped revisions are the stale frames it dropped.
Also prints the server's per-frame split (render + read-back on the GL thread, JPEG encode) from
the parts' headers. (The streamed JPEG against the PNG of the same frame: tests/http's
LiveStream test.)

Usage: python3 bench/stream_bench.py [--binary build/bin/volstyle] [--frames 30] [--sizes 960x540,1920x1080]
                                     [--viewport-sizes 320x320,480x480]
"""
import argparse
import http.client
import json
import math
import os
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from serverproc import BINARY, Server, percentile, request  # noqa: E402


class Stream:
    """Reads the MJPEG parts of …/stylizer/stream in a thread: (arrival time, headers, body)."""

    def __init__(self, port, path):
        self.conn = http.client.HTTPConnection("127.0.0.1", port, timeout=300)
        self.conn.request("GET", "/api/v1" + path)
        self.resp = self.conn.getresponse()
        assert self.resp.status == 200, self.resp.status
        assert self.resp.getheader("Content-Type").startswith("multipart/x-mixed-replace"), self.resp.getheader("Content-Type")
        self.parts = []
        self.cond = threading.Condition()
        self.thread = threading.Thread(target=self._read, daemon=True)
        self.thread.start()

    def _read(self):
        try:
            while True:
                line = self.resp.readline()
                if not line:
                    return
                if not line.startswith(b"--volstyle-frame"):
                    continue
                if line.strip().endswith(b"--"):
                    return
                headers = {}
                while True:
                    h = self.resp.readline().strip()
                    if not h:
                        break
                    k, v = h.decode().split(":", 1)
                    headers[k.strip().lower()] = v.strip()
                body = self.resp.read(int(headers.get("content-length", 0)))
                self.resp.readline()  # the part's CRLF
                with self.cond:
                    self.parts.append((time.monotonic(), headers, body))
                    self.cond.notify_all()
        except (OSError, http.client.HTTPException, ValueError, AttributeError):  # AttributeError: closed under the reader
            return

    def wait_revision(self, revision, timeout=300):
        """The first JPEG part of at least `revision`."""
        deadline = time.monotonic() + timeout
        with self.cond:
            while True:
                for p in self.parts:
                    if p[1].get("content-type") == "image/jpeg" and int(p[1]["x-revision"]) >= revision:
                        return p
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError(f"no frame of revision {revision}")
                self.cond.wait(left)

    def close(self):
        self.conn.close()


def put_scene(port, sid, scene):
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=120)
    c.request("PUT", f"/api/v1/sessions/{sid}/stylizer", body=json.dumps(scene), headers={"Content-Type": "application/json"})
    r = c.getresponse()
    r.read()
    assert r.status == 200, r.status
    return int(r.getheader("ETag").strip('"r'))


def run(port, sid, scene, size, frames):
    w, h = size
    scene = dict(scene)
    scene["camera"] = dict(scene["camera"], width=w, height=h)
    scene["time"] = 0.0
    stream = Stream(port, f"/sessions/{sid}/stylizer/stream")
    rev = put_scene(port, sid, scene)
    stream.wait_revision(rev)  # the scene now, before the timed loop
    # Closed loop: one change in flight.
    latencies, splits = [], []
    t_start = time.monotonic()
    for i in range(frames):
        scene["time"] = 0.05 * (i + 1)
        sent = time.monotonic()
        rev = put_scene(port, sid, scene)
        arrived, headers, _ = stream.wait_revision(rev)
        latencies.append((arrived - sent) * 1000)
        splits.append((float(headers["x-render-ms"]), float(headers["x-encode-ms"]), len(_)))
    closed_fps = frames / (time.monotonic() - t_start)
    # Open loop: changes at 60 Hz for as long as the closed loop took (at least 2 s).
    seconds = max(2.0, frames / max(closed_fps, 1e-3))
    before = len(stream.parts)
    t0 = time.monotonic()
    sent_revisions = []
    i = 0
    while time.monotonic() - t0 < seconds:
        scene["time"] = 10 + 0.01 * i
        sent_revisions.append(put_scene(port, sid, scene))
        i += 1
        time.sleep(max(0.0, t0 + i / 60.0 - time.monotonic()))
    last = stream.wait_revision(sent_revisions[-1])
    shown = [p for p in stream.parts[before:] if p[1].get("content-type") == "image/jpeg" and p[0] <= last[0]]
    open_fps = len(shown) / (last[0] - t0)
    dropped = len(sent_revisions) - len(shown)
    stream.close()
    render = [s[0] for s in splits]
    encode = [s[1] for s in splits]
    kib = sum(s[2] for s in splits) / len(splits) / 1024
    print(f"{w}x{h}: closed loop {closed_fps:.1f} fps, latency median {percentile(latencies, 50):.0f} ms, "
          f"p95 {percentile(latencies, 95):.0f} ms (render+read-back {percentile(render, 50):.0f} ms, "
          f"JPEG {percentile(encode, 50):.1f} ms, {kib:.0f} KiB a frame); "
          f"open loop (60 changes/s): {open_fps:.1f} fps shown, {dropped} of {len(sent_revisions)} revisions dropped as stale")
    sys.stdout.flush()


def put_viewport(port, sid, azimuth, size):
    w, h = size
    body = {"camera": {"eye": [3.4 * math.sin(azimuth), 0.2, 3.4 * math.cos(azimuth)], "target": [0, -0.05, 0], "fov_y_deg": 38,
                       "width": w, "height": h}}
    status, answer = request(port, "PUT", f"/sessions/{sid}/viewport", body)
    assert status == 200, answer
    return json.loads(answer)["revision"]


def run_viewport(port, sid, size, frames):
    """The page's viewport: each orbit step a PUT …/viewport, closed loop (one step in flight)."""
    stream = Stream(port, f"/sessions/{sid}/viewport/stream")
    stream.wait_revision(put_viewport(port, sid, 0, size))
    latencies, render = [], []
    t_start = time.monotonic()
    for i in range(frames):
        sent = time.monotonic()
        arrived, headers, _ = stream.wait_revision(put_viewport(port, sid, 0.05 * (i + 1), size))
        latencies.append((arrived - sent) * 1000)
        render.append(float(headers["x-render-ms"]))
    fps = frames / (time.monotonic() - t_start)
    stream.close()
    print(f"viewport {size[0]}x{size[1]} (64^3 cloud): closed loop {fps:.1f} fps, latency median {percentile(latencies, 50):.0f} ms, "
          f"p95 {percentile(latencies, 95):.0f} ms (render {percentile(render, 50):.0f} ms)")
    sys.stdout.flush()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", default=BINARY)
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--sizes", default="960x540,1920x1080")
    ap.add_argument("--viewport-sizes", default="320x320,480x480")
    a = ap.parse_args()
    parse = lambda text: [tuple(int(x) for x in s.split("x")) for s in text.split(",") if s]  # noqa: E731
    sizes = parse(a.sizes)
    with tempfile.TemporaryDirectory() as data:
        server = Server(data, binary=a.binary)
        try:
            status, body = request(server.port, "POST", "/sessions", {"scene": "builtin:cloud", "resolution": 16})
            assert status == 201, body
            sid = json.loads(body)["id"]
            status, body = request(server.port, "GET", f"/sessions/{sid}/stylizer")
            scene = json.loads(body)
            for size in sizes:
                run(server.port, sid, scene, size, a.frames)
            status, body = request(server.port, "POST", "/sessions", {"scene": "builtin:cloud", "resolution": 64})
            assert status == 201, body
            for size in parse(a.viewport_sizes):
                run_viewport(server.port, json.loads(body)["id"], size, a.frames)
        finally:
            server.stop()


if __name__ == "__main__":
    main()
