#!/usr/bin/env bash
# Validates answers against /api/v1/schema.json with ajv (installed into build/web-test by
# scripts/test.sh). Skips (77) without node or ajv.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
modules="$root/build/web-test/node_modules"
if ! command -v node >/dev/null || [ ! -d "$modules/ajv" ]; then
  echo "skipping: needs node and ajv in build/web-test (scripts/test.sh installs it)"
  exit 77
fi
exec bash "$root/tests/web/with_server.sh" "$1" env NODE_PATH="$modules" node "$root/tests/web/validate_api.cjs"
