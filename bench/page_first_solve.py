#!/usr/bin/env python3
"""The painting page's first solve, by the wall clock (issue #40 item 3): a fresh server, the
page's defaults (builtin:cloud at 64³, one 256² view, emission + albedo, Laplacian 0.002, 30
iterations), a target painted over the whole view, and the time from POST …/solve to the job's
end, with the solve report's set-up phases. Then the same solve again (the session's cache).
--paint-seconds S waits S seconds between adding the view and uploading its target, as an artist
paints: the server renders the view ahead of the solve meanwhile (--prefetch, on by default).

Usage: python3 bench/page_first_solve.py [--binary build/bin/volstyle] [--resolution 64] [--size 256] [--paint-seconds 0]
       [--prefetch on|off]
"""
import argparse
import json
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from serverproc import BINARY, Server, png, request  # noqa: E402


def solve(port, sid, options):
    t0 = time.monotonic()
    status, body = request(port, "POST", f"/sessions/{sid}/solve", options)
    assert status == 202, body
    job = json.loads(body)["job"]
    while True:
        status, body = request(port, "GET", f"/jobs/{job}")
        state = json.loads(body)
        if state["state"] in ("done", "failed", "cancelled"):
            break
        time.sleep(0.05)
    wall = time.monotonic() - t0
    assert state["state"] == "done", state
    return wall, state["result"]["report"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", default=BINARY)
    ap.add_argument("--resolution", type=int, default=64)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--paint-seconds", type=float, default=0)
    ap.add_argument("--prefetch", choices=("on", "off"), default="on")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as data:
        server = Server(data, binary=a.binary, extra=["--prefetch", a.prefetch])
        try:
            status, body = request(server.port, "POST", "/sessions", {"scene": "builtin:cloud", "resolution": a.resolution})
            assert status == 201, body
            sid = json.loads(body)["id"]
            camera = {"eye": [0.4, 0.5, 3.0], "target": [0, 0, 0], "width": a.size, "height": a.size}
            status, body = request(server.port, "POST", f"/sessions/{sid}/views", {"camera": camera})
            assert status in (200, 201), body
            vid = json.loads(body)["id"]
            time.sleep(a.paint_seconds)
            _, metrics = request(server.port, "GET", "/metrics")
            ahead = [line.split()[-1] for line in metrics.decode().splitlines() if line.startswith("volstyle_prefetched_views_total")]
            print(f"painting for {a.paint_seconds:g} s: {ahead[0] if ahead else '?'} view(s) rendered ahead (--prefetch {a.prefetch})")
            status, body = request(server.port, "PUT", f"/sessions/{sid}/views/{vid}/target", png(a.size, a.size, (200, 150, 110)),
                                   content_type="image/png")
            assert status == 200, body
            options = {"unknowns": ["emission", "albedo"], "regularization": {"laplacian": 0.002}, "max_iterations": 30}
            for label in ("first solve", "the same solve again"):
                wall, report = solve(server.port, sid, options)
                phases = ", ".join(f"{p['phase']} {p['ms']:.0f}" for p in report["setup"])
                n = max(report["iterations"], 1)
                per = (report["forward_ms"] + report["adjoint_ms"] + report["vector_ms"]) / n
                print(f"{a.resolution}³ cloud, one {a.size}² view, emission + albedo, {label}: {wall:.2f} s from POST to done; "
                      f"set-up {report['setup_ms'] / 1000:.2f} s ({phases} ms); {report['iterations']} iterations of {per:.0f} ms "
                      f"(forward {report['forward_ms'] / n:.0f}, back-projection {report['adjoint_ms'] / n:.0f}, vectors {report['vector_ms'] / n:.0f}); "
                      f"reach analysis {report['reach']['ms']:.0f} ms")
                sys.stdout.flush()
        finally:
            server.stop()


if __name__ == "__main__":
    main()
