"""`python -m volstyle_client` (or `volstyle-client`): a few calls from a shell.

    volstyle-client [--url URL] [--token T] health
    volstyle-client sessions | jobs [--session SID]
    volstyle-client wait JOB          # follows a job's progress, exits 1 if it failed
    volstyle-client cancel JOB
    volstyle-client download SID OUT.vdb [--version N]
"""
from __future__ import annotations

import argparse
import json
import os
import sys

from .client import Client
from .errors import JobFailed, VolstyleError


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="volstyle-client", description="Talk to a volstyle server.")
    p.add_argument("--url", default=os.environ.get("VOLSTYLE_URL", "http://127.0.0.1:8080"), help="the server (default $VOLSTYLE_URL or %(default)s)")
    p.add_argument("--token", default=None, help="bearer token (default $VOLSTYLE_TOKEN)")
    sub = p.add_subparsers(dest="command", required=True)
    sub.add_parser("health")
    sub.add_parser("sessions")
    jobs = sub.add_parser("jobs")
    jobs.add_argument("--session")
    for name in ("wait", "cancel"):
        sub.add_parser(name).add_argument("job")
    d = sub.add_parser("download")
    d.add_argument("session")
    d.add_argument("out")
    d.add_argument("--version", type=int)
    a = p.parse_args(argv)
    vs = Client(a.url, a.token)
    try:
        if a.command == "health":
            out = vs.health()
        elif a.command == "sessions":
            out = list(vs.iter_sessions())
        elif a.command == "jobs":
            out = list(vs.iter_jobs(a.session))
        elif a.command == "wait":
            out = vs.job(a.job).wait()
        elif a.command == "cancel":
            out = vs.cancel_job(a.job)
        else:
            vs.download_volume(a.session, a.version, path=a.out)
            out = {"written": a.out}
    except JobFailed as e:
        print(e, file=sys.stderr)
        return 1
    except VolstyleError as e:
        print(f"volstyle-client: {e}", file=sys.stderr)
        return 2
    json.dump(out, sys.stdout, indent=1)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
