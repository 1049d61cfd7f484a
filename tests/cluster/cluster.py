#!/usr/bin/env python3
"""A local volstyle cluster (issue #41, docs/DEPLOY.md): N replicas of `volstyle serve` sharing one
PostgreSQL store, behind HAProxy on 127.0.0.1. The balancer hashes a session's id (and a job's,
whose first 8 hex digits are its session's) from the path, so a session's requests go to one
replica while it is up; health checks on /api/v1/ready take a dead replica out within ~0.6 s and
its sessions move to the others, which read them from the store.

As a program (scripts/cluster.sh starts PostgreSQL and runs it): serves until Ctrl-C.
    python3 tests/cluster/cluster.py [--replicas 3] [--port 8080]   (needs $VOLSTYLE_TEST_STORE)
As a module: Cluster(store_url, replicas=3).start(); .url, .replica_url(i), .kill(i), .restart(i).
"""
import argparse
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BINARY = os.environ.get("VOLSTYLE_BINARY", os.path.join(ROOT, "build", "bin", "volstyle"))

HAPROXY_CONFIG = """global
    maxconn 2000
defaults
    mode http
    timeout connect 2s
    timeout client 600s
    timeout server 600s
    timeout check 2s
    # A request that cannot reach its replica (killed, restarting) goes to another.
    option redispatch
    retries 3
frontend volstyle
    bind 127.0.0.1:{port}
    http-response set-header X-Volstyle-Replica %[srv_name]
    acl keyed path_beg /api/v1/sessions/ /api/v1/jobs/
    use_backend by_session if keyed
    default_backend any
backend by_session
    # The session id (a job id's first 8 hex digits are its session's): field 5 of
    # /api/v1/sessions/<sid>/… and /api/v1/jobs/<jid>.
    balance hash path,field(5,/),bytes(0,8)
    hash-type consistent
    option httpchk GET /api/v1/ready
    http-check expect status 200
    default-server inter 300ms fall 2 rise 2 on-marked-down shutdown-sessions
{servers}
backend any
    balance roundrobin
{tracked}
"""


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_ready(url, seconds=60):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(url + "/api/v1/ready", timeout=2) as r:
                if r.status == 200:
                    return
        except OSError:
            pass
        time.sleep(0.1)
    raise RuntimeError(f"{url} was not ready in {seconds} s")


class Cluster:
    def __init__(self, store, replicas=3, port=0, binary=BINARY, quiet=True, job_lease=10.0):
        self.store, self.n, self.binary, self.quiet, self.job_lease = store, replicas, binary, quiet, job_lease
        self.port = port or free_port()
        self.ports = [free_port() for _ in range(replicas)]
        self.dir = tempfile.mkdtemp(prefix="volstyle-cluster-")
        self.procs = [None] * replicas
        self.haproxy = None

    @property
    def url(self):
        return f"http://127.0.0.1:{self.port}"

    def replica_url(self, i):
        return f"http://127.0.0.1:{self.ports[i]}"

    def log(self, i):
        return os.path.join(self.dir, f"r{i + 1}.log")

    def start_replica(self, i, wait=True):
        # Each replica a data folder of its own: the store's cache, filled from it at start.
        data = os.path.join(self.dir, f"r{i + 1}")
        with open(self.log(i), "a") as log:
            self.procs[i] = subprocess.Popen([self.binary, "serve", "--port", str(self.ports[i]), "--data-dir", data, "--store", self.store,
                                              "--replica", f"r{i + 1}", "--job-lease", str(self.job_lease),
                                              "--web-dir", os.path.join(ROOT, "web")], stdout=log, stderr=subprocess.STDOUT)
        if wait:
            wait_ready(self.replica_url(i))

    def start(self):
        for i in range(self.n):
            self.start_replica(i, wait=False)
        for i in range(self.n):
            wait_ready(self.replica_url(i))
        servers = "\n".join(f"    server r{i + 1} 127.0.0.1:{p} check" for i, p in enumerate(self.ports))
        tracked = "\n".join(f"    server r{i + 1} 127.0.0.1:{p} track by_session/r{i + 1}" for i, p in enumerate(self.ports))
        config = os.path.join(self.dir, "haproxy.cfg")
        with open(config, "w") as f:
            f.write(HAPROXY_CONFIG.format(port=self.port, servers=servers, tracked=tracked))
        self.haproxy = subprocess.Popen(["haproxy", "-f", config, "-db"], stdout=subprocess.DEVNULL if self.quiet else None,
                                        stderr=subprocess.STDOUT if self.quiet else None)
        wait_ready(self.url)
        return self

    def kill(self, i):
        """kill -9: no shutdown, no flush; what was acknowledged must already be in the store."""
        p = self.procs[i]
        if p and p.poll() is None:
            p.send_signal(signal.SIGKILL)
            p.wait()

    def restart(self, i, wait=True):
        self.kill(i)
        self.start_replica(i, wait)

    def stop(self):
        for p in self.procs + [self.haproxy]:
            if p and p.poll() is None:
                p.terminate()
        for p in self.procs + [self.haproxy]:
            if p:
                try:
                    p.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    p.kill()
        shutil.rmtree(self.dir, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--replicas", type=int, default=3)
    ap.add_argument("--port", type=int, default=8080)
    a = ap.parse_args()
    store = os.environ.get("VOLSTYLE_TEST_STORE")
    if not store:
        sys.exit("cluster.py: set VOLSTYLE_TEST_STORE=postgresql://… (scripts/cluster.sh starts a PostgreSQL and sets it)")
    c = Cluster(store, a.replicas, a.port, quiet=False).start()
    print(f"volstyle cluster: {c.url}/ (HAProxy) → " + ", ".join(c.replica_url(i) for i in range(c.n)) + f"; store {store}; logs in {c.dir}")
    sys.stdout.flush()
    try:
        signal.sigwait({signal.SIGINT, signal.SIGTERM})
    finally:
        c.stop()


if __name__ == "__main__":
    main()
