#!/usr/bin/env python3
"""Requests per second and latency through HAProxy with 1, 2 and 3 replicas on one PostgreSQL store
(issue #41). Each run starts a fresh cluster (tests/cluster/cluster.py), makes 12 sessions (16³
sphere), then 8 client threads for --seconds send a mix through the balancer: 60% reads
(GET the session), 25% small renders (POST …/render, 32², JPEG), 15% edits (POST/DELETE
…/refraction: a new version, committed to the store before the answer). Prints, per replica count,
requests/s, p50/p99 latency in all and per kind, and how the sessions spread over the replicas.
On this 2-core machine the cores cap it: the point is that work spreads and nothing is refused.

Usage: tests/cluster/with_postgres.sh python3 bench/cluster_load.py [--replicas 1,2,3] [--seconds 20]
"""
import argparse
import collections
import json
import os
import random
import sys
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "cluster"))
from cluster import Cluster  # noqa: E402
from cluster_test import call  # noqa: E402


def percentile(values, p):
    v = sorted(values)
    return v[min(len(v) - 1, int(round(p / 100 * (len(v) - 1))))] if v else float("nan")


def run(store, replicas, seconds, clients=8, sessions=12):
    c = Cluster(store, replicas).start()
    try:
        sids = []
        for _ in range(sessions):
            status, body, _ = call(c.url + "/api/v1/sessions", "POST", {"scene": "builtin:sphere", "resolution": 16}, retry_seconds=10)
            assert status == 201, body
            sids.append(json.loads(body)["id"])
        lat = collections.defaultdict(list)
        served = collections.Counter()
        errors = collections.Counter()
        lock = threading.Lock()
        stop = time.monotonic() + seconds
        camera = {"eye": [0, 0.2, 3], "target": [0, 0, 0], "width": 32, "height": 32}

        def client(k):
            rng = random.Random(k)
            while time.monotonic() < stop:
                sid = rng.choice(sids)
                base = f"{c.url}/api/v1/sessions/{sid}"
                x = rng.random()
                t0 = time.monotonic()
                if x < 0.60:
                    kind, (status, _, h) = "read", call(base)
                elif x < 0.85:
                    kind, (status, _, h) = "render", call(base + "/render", "POST", {"camera": camera, "format": "jpeg"})
                else:
                    kind = "edit"
                    status, _, h = call(base + "/refraction", "POST", {"index": 1.2, "radius": 0.4}) if rng.random() < 0.5 else \
                        call(base + "/refraction", "DELETE")
                    status = 200 if status == 400 else status  # DELETE with no glass: refused by name, still an answer
                ms = (time.monotonic() - t0) * 1000
                with lock:
                    if status == 200:
                        lat[kind].append(ms)
                        served[(sid, h.get("x-volstyle-replica"))] += 1
                    else:
                        errors[status] += 1
                        if errors[status] == 1:
                            print(f"  the first {status} ({kind}): {_[:200]!r}")

        threads = [threading.Thread(target=client, args=(k,)) for k in range(clients)]
        t0 = time.monotonic()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        wall = time.monotonic() - t0
        every = [x for v in lat.values() for x in v]
        per_replica = collections.Counter(r for (_, r) in served)
        sessions_per = collections.Counter()
        for sid in sids:
            owners = {r for (s, r) in served if s == sid}
            sessions_per[len(owners)] += 1
        kinds = ", ".join(f"{k} {len(v)} (p50 {percentile(v, 50):.0f}, p99 {percentile(v, 99):.0f} ms)" for k, v in sorted(lat.items()))
        print(f"{replicas} replica(s): {len(every) / wall:.1f} requests/s, p50 {percentile(every, 50):.0f} ms, p99 {percentile(every, 99):.0f} ms; "
              f"{kinds}; sessions by replica {dict(sorted(per_replica.items()))}; each session by one replica: "
              f"{sessions_per[1] == len(sids)}; errors {dict(errors) or 'none'}")
        sys.stdout.flush()
    finally:
        c.stop()


def store_overhead(store, edits=40, jobs=20):
    """One replica, no balancer, with the data folder alone and with the PostgreSQL store: the
    median of `edits` sequential edits (a new 16³ version each, written before the answer), and of
    `jobs` sequential one-iteration solves (16³, one 16² view) from POST …/solve to the end of the
    job's event stream. With the store a job is also a row of the job queue: added, written when
    it runs and when it ends, its events sent through NOTIFY; the difference is the queue's cost."""
    import subprocess
    import tempfile
    import urllib.request
    from cluster import BINARY, free_port, wait_ready
    from cluster_test import png
    edit_out, job_out, medians = [], [], {}
    for label, extra in (("data folder", []), ("PostgreSQL store", ["--store", store])):
        with tempfile.TemporaryDirectory() as data:
            port = free_port()
            p = subprocess.Popen([BINARY, "serve", "--port", str(port), "--data-dir", data, *extra], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            try:
                url = f"http://127.0.0.1:{port}"
                wait_ready(url)
                status, body, _ = call(url + "/api/v1/sessions", "POST", {"scene": "builtin:sphere", "resolution": 16})
                base = f"{url}/api/v1/sessions/{json.loads(body)['id']}"
                ms = []
                for k in range(edits):
                    t0 = time.monotonic()
                    status, _, _ = call(base + "/refraction", "POST" if k % 2 == 0 else "DELETE", {"index": 1.2, "radius": 0.4} if k % 2 == 0 else None)
                    assert status == 200, status
                    ms.append((time.monotonic() - t0) * 1000)
                edit_out.append(f"{label} {percentile(ms, 50):.1f} ms (p90 {percentile(ms, 90):.1f})")
                medians["edit " + label] = percentile(ms, 50)
                status, body, _ = call(base + "/views", "POST", {"camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "width": 16, "height": 16}})
                status, _, _ = call(f"{base}/views/{json.loads(body)['id']}/target", "PUT", raw=png(16, 16, 128))
                assert status in (200, 201), status
                ms = []
                for _ in range(jobs):
                    t0 = time.monotonic()
                    status, body, _ = call(base + "/solve", "POST", {"max_iterations": 1})
                    assert status == 202, body
                    with urllib.request.urlopen(f"{url}/api/v1/jobs/{json.loads(body)['job']}/events", timeout=60) as r:
                        r.read()
                    ms.append((time.monotonic() - t0) * 1000)
                medians[label] = percentile(ms, 50)
                job_out.append(f"{label} {percentile(ms, 50):.1f} ms (p90 {percentile(ms, 90):.1f})")
            finally:
                p.terminate()
                p.wait()
    print("an edit's latency, one replica, median of %d: " % edits + "; ".join(edit_out))
    print("a one-iteration solve job, POST to its last event, median of %d: " % jobs + "; ".join(job_out) +
          f"; the store's cost per job {medians['PostgreSQL store'] - medians['data folder']:.1f} ms, of which the job queue's "
          f"(less one edit's store cost: a job commits one version) {medians['PostgreSQL store'] - medians['data folder'] - (medians['edit PostgreSQL store'] - medians['edit data folder']):.1f} ms")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--replicas", default="1,2,3")
    ap.add_argument("--seconds", type=float, default=20)
    a = ap.parse_args()
    store = os.environ.get("VOLSTYLE_TEST_STORE")
    if not store:
        sys.exit("cluster_load.py: run under tests/cluster/with_postgres.sh")
    store_overhead(store)
    for n in (int(x) for x in a.replicas.split(",")):
        run(store, n, a.seconds)


if __name__ == "__main__":
    main()
