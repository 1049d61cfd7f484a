#!/usr/bin/env python3
"""What work ahead costs a request that arrives while it runs (issue #40): a fresh server, the
paper's cloud at 128³ with two 480² views whose renders and rows the GL thread makes while idle
(--prefetch on), and small renders (64², the page's thumbnails) requested every --interval seconds
meanwhile (a request interrupts the view in progress, which starts again at the next quiet moment).
Each request's wall time against the same requests with --prefetch off: work ahead must yield
within a chunk (2^13 pixels). Prints the median and worst of each, and how many views were made.

Usage: python3 bench/work_ahead_latency.py [--binary build/bin/volstyle] [--requests 12] [--interval 2]
"""
import argparse
import json
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from serverproc import BINARY, Server, percentile, request  # noqa: E402


def made(port):
    _, metrics = request(port, "GET", "/metrics")
    return {line.split('"')[1]: float(line.split()[-1]) for line in metrics.decode().splitlines()
            if line.startswith("volstyle_prefetched_views_total{")}


def run(binary, prefetch, requests, interval):
    with tempfile.TemporaryDirectory() as data:
        server = Server(data, binary=binary, extra=["--prefetch", prefetch])
        try:
            status, body = request(server.port, "POST", "/sessions", {"scene": "builtin:cloud", "resolution": 128})
            assert status == 201, body
            sid = json.loads(body)["id"]
            for eye in ([0.4, 0.5, 3.0], [-2.6, 0.4, 1.5]):
                status, body = request(server.port, "POST", f"/sessions/{sid}/views",
                                       {"camera": {"eye": eye, "target": [0, 0, 0], "width": 480, "height": 480}})
                assert status in (200, 201), body
            small = {"camera": {"eye": [0, 0.2, 3.4], "target": [0, 0, 0], "width": 64, "height": 64}, "format": "png"}
            times = []
            for _ in range(requests):
                time.sleep(interval)  # past the GL thread's quiet moment: work ahead has started
                t0 = time.monotonic()
                status, body = request(server.port, "POST", f"/sessions/{sid}/render", small)
                assert status == 200, body
                times.append(time.monotonic() - t0)
            return times, made(server.port)
        finally:
            server.stop()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", default=BINARY)
    ap.add_argument("--requests", type=int, default=12)
    ap.add_argument("--interval", type=float, default=2.0)
    a = ap.parse_args()
    for prefetch in ("off", "on"):
        times, views = run(a.binary, prefetch, a.requests, a.interval)
        ms = [1000 * t for t in times]
        print(f"--prefetch {prefetch}, a request every {a.interval:g} s: a 64² render while the server is idle or working ahead: median {percentile(ms, 50):.0f} ms, "
              f"worst {max(ms):.0f} ms over {len(ms)} requests; made ahead meanwhile: {views or 'nothing'}")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
