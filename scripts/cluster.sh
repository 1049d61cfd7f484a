#!/usr/bin/env bash
# A local volstyle cluster on 127.0.0.1 (docs/DEPLOY.md): a private PostgreSQL, N replicas of
# `volstyle serve --store postgresql://…` and HAProxy hashing sessions onto them; Ctrl-C stops all.
# Usage: scripts/cluster.sh [--replicas 3] [--port 8080]   (after scripts/run.sh or build.sh)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/install_deps.sh"
[ -x "$root/build/bin/volstyle" ] || bash "$root/scripts/build.sh"
exec bash "$root/tests/cluster/with_postgres.sh" python3 "$root/tests/cluster/cluster.py" "$@"
