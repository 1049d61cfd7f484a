#!/usr/bin/env python3
"""Soak (issue #9): 8 clients for 10 minutes against `volstyle serve`, mixing renders, solves,
uploads, reverts, downloads, cancels and deletes, while a prober times /health and a sampler
reads the server's RSS.

    python3 bench/soak.py [--seconds 600] [--clients 8] [--warmup 120] [--json OUT]

Pass criteria (printed): 0 answers beyond the expected ones, /health p99 < 100 ms, RSS growth
<= 5 % between the first and the last minute after the warm-up."""
import argparse
import json
import random
import shutil
import sys
import tempfile
import threading
import time

from serverproc import Server, percentile, png, request

CAMERA = {"eye": [0, 0.2, 3.2], "target": [0, 0, 0], "width": 24, "height": 24}
# What each action may answer besides success: a session's queue is full (422), the job ended
# before its cancel (404/409 are not expected: cancel of an ended job answers 202).
EXPECTED = {"solve": {422}, "create": {422}}


class Stats:
    def __init__(self):
        self.lock = threading.Lock()
        self.counts = {}
        self.unexpected = []

    def record(self, action, status, ok_statuses):
        with self.lock:
            self.counts[action] = self.counts.get(action, 0) + 1
            if status not in ok_statuses and status not in EXPECTED.get(action, set()):
                self.unexpected.append((action, status))


def client(port, stats, stop, seed):
    rnd = random.Random(seed)
    sessions = []  # [sid, views, versions]

    def call(action, method, path, body=None, ok=(200,), ctype="application/json"):
        status, payload = request(port, method, path, body, ctype)
        stats.record(action, status, set(ok))
        return status, payload

    while not stop.is_set():
        if len(sessions) < 2 or (len(sessions) < 3 and rnd.random() < 0.05):
            st, p = call("create", "POST", "/sessions", {"scene": rnd.choice(["builtin:sphere", "builtin:cloud"]),
                                                         "resolution": rnd.choice([16, 24, 32])}, ok=(201,))
            if st == 201:
                sessions.append([json.loads(p)["id"], 0, 1])
            continue
        s = rnd.choice(sessions)
        base = "/sessions/" + s[0]
        r = rnd.random()
        if r < 0.25:
            call("render", "POST", base + "/render", {"camera": CAMERA, "format": rnd.choice(["png", "exr"])})
        elif r < 0.35:
            st, _ = call("view", "POST", base + "/views", {"camera": CAMERA}, ok=(201,))
            if st == 201:
                s[1] += 1
                call("target", "PUT", f"{base}/views/v{s[1]}/target", png(24, 24, (rnd.randrange(256), 120, 60)),
                     ctype="image/png")
        elif r < 0.45 and s[1] > 0:
            st, p = call("solve", "POST", base + "/solve", {"max_iterations": rnd.choice([3, 6]),
                                                               "resolution": {"emission": [16, 16, 16]}}, ok=(202,))
            if st == 202 and rnd.random() < 0.4:
                time.sleep(rnd.random() * 0.5)
                call("cancel", "DELETE", "/jobs/" + json.loads(p)["job"], ok=(202,))
        elif r < 0.55:
            st, p = call("get", "GET", base)
            if st == 200:
                s[2] = json.loads(p)["volume"]["version"]
                call("revert", "POST", base + "/revert", {"version": rnd.randint(1, s[2])})
        elif r < 0.65:
            st, vdb = call("download", "GET", base + "/volume.vdb")
            if st == 200 and rnd.random() < 0.5:
                call("upload", "PUT", base + "/volume", vdb, ctype="application/octet-stream")
        elif r < 0.70:
            call("delete", "DELETE", base, ok=(204,))
            sessions.remove(s)
        elif r < 0.80 and s[1] > 0:
            call("view_render", "GET", f"{base}/views/v{rnd.randint(1, s[1])}/render.png")
        else:
            call("lighting", "PUT", base + "/lighting",
                 {"sun": {"direction": [rnd.uniform(-1, 1), 1, 0.2], "irradiance": [5, 5, 5]}, "background": [0.2, 0.3, 0.4]})
    for s in sessions:
        request(port, "DELETE", "/sessions/" + s[0])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=600)
    ap.add_argument("--clients", type=int, default=8)
    ap.add_argument("--warmup", type=float, default=120)
    ap.add_argument("--json")
    a = ap.parse_args()
    data = tempfile.mkdtemp(prefix="volstyle-soak-")
    server = Server(data)
    stats, stop = Stats(), threading.Event()
    health, rss = [], []

    def probe():
        while not stop.is_set():
            t0 = time.monotonic()
            st, _ = request(server.port, "GET", "/health", timeout=30)
            health.append(((time.monotonic() - t0) * 1000, st))
            time.sleep(0.2)

    def sample():
        t0 = time.monotonic()
        while not stop.is_set():
            rss.append((time.monotonic() - t0, server.rss_mib()))
            time.sleep(5)

    threads = [threading.Thread(target=client, args=(server.port, stats, stop, i)) for i in range(a.clients)]
    threads += [threading.Thread(target=probe), threading.Thread(target=sample)]
    for t in threads:
        t.start()
    t_start = time.monotonic()
    try:
        while time.monotonic() - t_start < a.seconds:
            time.sleep(10)
            print(f"  {time.monotonic() - t_start:5.0f} s  requests {sum(stats.counts.values()):6d}  "
                  f"unexpected {len(stats.unexpected)}  rss {rss[-1][1] if rss else 0:.0f} MiB", flush=True)
    finally:
        stop.set()
        for t in threads:
            t.join()
        server.stop()
        shutil.rmtree(data, ignore_errors=True)
    ms = [m for m, st in health if st == 200]
    failed_probes = sum(1 for _, st in health if st != 200)
    after = [(t, m) for t, m in rss if t >= a.warmup]
    first = [m for t, m in after if t < a.warmup + 60]
    last = [m for t, m in after if t >= a.seconds - 60]
    growth = (sum(last) / len(last) / (sum(first) / len(first)) - 1) * 100 if first and last else float("nan")
    result = {
        "seconds": a.seconds, "clients": a.clients, "requests": sum(stats.counts.values()), "by_action": stats.counts,
        "unexpected": len(stats.unexpected), "unexpected_examples": stats.unexpected[:10],
        "health_probes": len(health), "health_failed": failed_probes,
        "health_p50_ms": percentile(ms, 50), "health_p99_ms": percentile(ms, 99), "health_max_ms": max(ms) if ms else None,
        "rss_first_minute_after_warmup_mib": sum(first) / len(first) if first else None,
        "rss_last_minute_mib": sum(last) / len(last) if last else None, "rss_growth_percent": growth,
        "rss_peak_mib": max(m for _, m in rss) if rss else None,
    }
    print(json.dumps(result, indent=2))
    ok = result["unexpected"] == 0 and failed_probes == 0 and result["health_p99_ms"] < 100 and growth <= 5
    print("soak:", "PASS" if ok else "FAIL")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(result, f, indent=2)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
