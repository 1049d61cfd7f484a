#!/usr/bin/env python3
"""Crash loop (issue #9): SIGKILL `volstyle serve` at random moments during uploads, commits and
solves, restart it on the same data directory, and check that every change the server
acknowledged (answered 2xx) is still there.

    python3 bench/kill_loop.py [--kills 20] [--json OUT]

Checked after each restart: acknowledged sessions exist; every acknowledged version number
(revert, upload, finished solve) is listed and the current version is at least the newest
acknowledged one; acknowledged targets are there; the lighting is the last acknowledged one (or
the one in flight at the kill)."""
import argparse
import json
import random
import shutil
import sys
import tempfile
import threading
import time

from serverproc import Server, percentile, png, request

CAMERA = {"eye": [0, 0, 3], "target": [0, 0, 0], "width": 16, "height": 16}


class Acked:
    def __init__(self):
        self.lock = threading.Lock()
        self.sessions = {}  # sid -> {"version": n, "versions": set, "targets": set, "lighting": [..], "pending": [..]}
        self.changes = 0
        self.by_kind = {}

    def note(self, sid, kind="create", **kw):
        with self.lock:
            self.by_kind[kind] = self.by_kind.get(kind, 0) + 1
            s = self.sessions.setdefault(sid, {"version": 1, "versions": {1}, "targets": set(), "lighting": None, "pending": None})
            if "version" in kw:
                s["versions"].add(kw["version"])
                s["version"] = max(s["version"], kw["version"])
            if "target" in kw:
                s["targets"].add(kw["target"])
            if "lighting" in kw:
                s["lighting"] = kw["lighting"]
            self.changes += 1


def worker(port, acked, stop, rnd):
    # Carry on with sessions of earlier rounds (the server keeps at most 64), then add new ones.
    with acked.lock:
        earlier = rnd.sample(sorted(acked.sessions), min(2, len(acked.sessions)))
    mine = []
    for sid in earlier:
        st, p = request(port, "GET", "/sessions/" + sid)
        if st == 200:
            mine.append([sid, len(json.loads(p)["views"])])
    while not stop.is_set():
        if not mine or (len(acked.sessions) < 48 and rnd.random() < 0.1):
            st, p = request(port, "POST", "/sessions", {"scene": "builtin:sphere", "resolution": rnd.choice([16, 24])})
            if st == 201:
                sid = json.loads(p)["id"]
                acked.note(sid)
                mine.append([sid, 0])
            continue
        s = rnd.choice(mine)
        base = "/sessions/" + s[0]
        r = rnd.random()
        if r < 0.2:
            irr = [round(rnd.uniform(1, 9), 3)] * 3
            with acked.lock:
                acked.sessions[s[0]]["pending"] = irr
            if request(port, "PUT", base + "/lighting", {"sun": {"direction": [0, 1, 0], "irradiance": irr}})[0] == 200:
                acked.note(s[0], "lighting", lighting=irr)
        elif r < 0.4:
            st, p = request(port, "POST", base + "/views", {"camera": CAMERA})
            if st == 201:
                vid = json.loads(p)["id"]
                s[1] += 1
                if request(port, "PUT", f"{base}/views/{vid}/target", png(16, 16, (200, 100, 50)), "image/png")[0] == 200:
                    acked.note(s[0], "target", target=vid)
        elif r < 0.6:
            st, p = request(port, "POST", base + "/revert", {"version": 1})
            if st == 200:
                acked.note(s[0], "revert", version=json.loads(p)["volume"]["version"])
        elif r < 0.75:
            st, vdb = request(port, "GET", base + "/volume.vdb")
            if st == 200:
                st, p = request(port, "PUT", base + "/volume", vdb, "application/octet-stream")
                if st == 200:
                    acked.note(s[0], "upload", version=json.loads(p)["volume"]["version"])
        elif s[1] > 0:
            st, p = request(port, "POST", base + "/solve", {"max_iterations": 4, "resolution": {"emission": [16, 16, 16]}})
            if st == 202:
                job = json.loads(p)["job"]
                while not stop.is_set():
                    st, p = request(port, "GET", "/jobs/" + job)
                    if st != 200:
                        break
                    j = json.loads(p)
                    if j["state"] == "done":
                        acked.note(s[0], "solve", version=j["result"]["version"])
                        break
                    if j["state"] in ("failed", "cancelled"):
                        break
                    time.sleep(0.05)


def verify(port, acked):
    checks, lost = 0, []
    for sid, a in acked.sessions.items():
        st, p = request(port, "GET", "/sessions/" + sid)
        checks += 1
        if st != 200:
            lost.append(f"session {sid}: {st}")
            continue
        s = json.loads(p)
        listed = set(s.get("versions", []))
        for n in a["versions"]:
            checks += 1
            if n not in listed:
                lost.append(f"session {sid}: version {n} not listed")
        checks += 1
        if s["volume"]["version"] < a["version"]:
            lost.append(f"session {sid}: current version {s['volume']['version']} < acknowledged {a['version']}")
        has = {v["id"] for v in s["views"] if v["has_target"]}
        for vid in a["targets"]:
            checks += 1
            if vid not in has:
                lost.append(f"session {sid}: target of {vid} lost")
        if a["lighting"] is not None:
            checks += 1
            irr = s["lighting"].get("sun", {}).get("irradiance")
            if irr not in (a["lighting"], a["pending"]):
                lost.append(f"session {sid}: lighting {irr}, acknowledged {a['lighting']}")
    return checks, lost


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--kills", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json")
    a = ap.parse_args()
    rnd = random.Random(a.seed)
    data = tempfile.mkdtemp(prefix="volstyle-kill-")
    acked = Acked()
    startup, total_checks, all_lost = [], 0, []
    try:
        for k in range(a.kills + 1):
            t0 = time.monotonic()
            server = Server(data)
            while request(server.port, "GET", "/health", timeout=5)[0] != 200:
                time.sleep(0.01)
            startup.append((time.monotonic() - t0) * 1000)
            checks, lost = verify(server.port, acked)
            total_checks += checks
            all_lost += lost
            print(f"  restart {k:2d}: listening after {startup[-1]:6.0f} ms, {checks} checks, {len(lost)} lost "
                  f"({acked.changes} changes acknowledged so far)", flush=True)
            for line in lost:
                print("    LOST", line)
            if k == a.kills:
                server.stop()
                break
            stop = threading.Event()
            threads = [threading.Thread(target=worker, args=(server.port, acked, stop, random.Random(rnd.random())))
                       for _ in range(3)]
            for t in threads:
                t.start()
            time.sleep(rnd.uniform(0.5, 4.0))
            server.kill()  # SIGKILL, mid-whatever
            stop.set()
            for t in threads:
                t.join()
    finally:
        shutil.rmtree(data, ignore_errors=True)
    result = {"kills": a.kills, "acknowledged_changes": acked.changes, "by_kind": acked.by_kind, "checks": total_checks, "lost": len(all_lost),
              "restart_p50_ms": percentile(startup, 50), "restart_max_ms": max(startup)}
    print(json.dumps(result, indent=2))
    print("kill loop:", "PASS" if not all_lost else "FAIL")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(result, f, indent=2)
    sys.exit(0 if not all_lost else 1)


if __name__ == "__main__":
    main()
