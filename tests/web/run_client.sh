#!/usr/bin/env bash
# Runs docs/examples/client.py (standard library only) against a fresh `volstyle serve`.
set -euo pipefail
binary=$1
root=$(cd "$(dirname "$0")/../.." && pwd)
command -v python3 >/dev/null || { echo "skipping: no python3"; exit 77; }
data=$(mktemp -d)
out=$(mktemp)
"$binary" serve --port 0 --data-dir "$data" --web-dir "$root/web" > "$out" 2>&1 &
server=$!
trap 'kill $server 2>/dev/null; wait $server 2>/dev/null; rm -rf "$data" "$out"' EXIT
for _ in $(seq 100); do
  port=$(sed -n 's|^volstyle: serving http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$out")
  [ -n "$port" ] && break
  sleep 0.1
done
[ -n "$port" ] || { echo "the server did not start:"; cat "$out"; exit 1; }
python3 "$root/docs/examples/client.py" "http://127.0.0.1:$port" "$data/solved.vdb"
"$binary" info "$data/solved.vdb" | grep -q "emission" || { echo "the solved VDB has no emission grid"; exit 1; }
echo "1 passed, 0 failed"
