#!/usr/bin/env bash
# Runs docs/examples/client.py (standard library only) against a fresh server.
set -euo pipefail
command -v python3 >/dev/null || { echo "skipping: no python3"; exit 77; }
root=$(cd "$(dirname "$0")/../.." && pwd)
exec bash "$root/tests/web/with_server.sh" "$1" bash -c '
  python3 "$VOLSTYLE_ROOT/docs/examples/client.py" "$VOLSTYLE_URL" "$VOLSTYLE_DATA/solved.vdb" &&
  "$VOLSTYLE_BINARY" info "$VOLSTYLE_DATA/solved.vdb" | grep -q emission &&
  echo "1 passed, 0 failed"'
