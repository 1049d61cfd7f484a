#!/usr/bin/env bash
# Validates /api/v1/openapi.json with @seriousme/openapi-schema-validator (installed into
# build/web-test by scripts/test.sh). Skips (77) without node or the validator.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
modules="$root/build/web-test/node_modules"
if ! command -v node >/dev/null || [ ! -d "$modules/@seriousme/openapi-schema-validator" ]; then
  echo "skipping: needs node and @seriousme/openapi-schema-validator in build/web-test (scripts/test.sh installs it)"
  exit 77
fi
# An ES module finds its packages from its own folder up: run a copy beside node_modules.
cp "$root/tests/web/validate_openapi.mjs" "$root/build/web-test/validate_openapi.mjs"
exec bash "$root/tests/web/with_server.sh" "$1" node "$root/build/web-test/validate_openapi.mjs"
