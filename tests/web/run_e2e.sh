#!/usr/bin/env bash
# Runs tests/web/e2e.cjs against a fresh `volstyle serve` on a free loopback port. Exits 77 (CTest
# skip) when chromium or node is missing. playwright-core is installed into build/web-test by
# scripts/test.sh (npm); the browser is Debian's chromium, never downloaded.
set -euo pipefail
binary=$1
root=$(cd "$(dirname "$0")/../.." && pwd)
modules="$root/build/web-test/node_modules"
if ! command -v node >/dev/null || [ ! -x /usr/bin/chromium ] || [ ! -d "$modules/playwright-core" ]; then
  echo "skipping: needs node, /usr/bin/chromium and playwright-core in build/web-test (scripts/test.sh installs them)"
  exit 77
fi
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
mkdir -p "$root/build/test-artifacts"
NODE_PATH="$modules" node "$root/tests/web/e2e.cjs" "http://127.0.0.1:$port/" "$root/build/test-artifacts/e2e.png"
