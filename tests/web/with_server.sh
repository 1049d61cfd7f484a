#!/usr/bin/env bash
# with_server.sh BINARY COMMAND… — starts `volstyle serve` (with $VOLSTYLE_SERVE_ARGS, if set) on a free loopback port with a fresh
# data directory, runs COMMAND with VOLSTYLE_URL set (e.g. http://127.0.0.1:41234), then stops
# the server. Exits 77 (CTest skip) when COMMAND's prerequisites are missing (checked by COMMAND).
set -euo pipefail
binary=$1
shift
root=$(cd "$(dirname "$0")/../.." && pwd)
data=$(mktemp -d)
out=$(mktemp)
"$binary" serve --port 0 --data-dir "$data" --web-dir "$root/web" ${VOLSTYLE_SERVE_ARGS:-} > "$out" 2>&1 &
server=$!
# On a failure the server's own log is printed: what it was doing is the first clue.
trap 'rc=$?; set +e; kill $server 2>/dev/null; wait $server 2>/dev/null; [ $rc -eq 0 ] || [ $rc -eq 77 ] || { echo "--- the server log (last 40 lines):"; tail -n 40 "$out"; }; rm -rf "$data" "$out"' EXIT
port=
for _ in $(seq 100); do
  port=$(sed -n 's|^volstyle: serving http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$out")
  [ -n "$port" ] && break
  sleep 0.1
done
[ -n "$port" ] || { echo "the server did not start:"; cat "$out"; exit 1; }
export VOLSTYLE_URL="http://127.0.0.1:$port" VOLSTYLE_DATA="$data" VOLSTYLE_ROOT="$root" VOLSTYLE_BINARY="$binary" VOLSTYLE_SERVER_PID="$server"
"$@"
