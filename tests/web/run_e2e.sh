#!/usr/bin/env bash
# The browser test: headless Debian chromium + playwright-core (installed into build/web-test by
# scripts/test.sh; the browser is never downloaded). Skips (77) without them.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
modules="$root/build/web-test/node_modules"
if ! command -v node >/dev/null || [ ! -x /usr/bin/chromium ] || [ ! -d "$modules/playwright-core" ]; then
  echo "skipping: needs node, /usr/bin/chromium and playwright-core in build/web-test (scripts/test.sh installs them)"
  exit 77
fi
mkdir -p "$root/build/test-artifacts"
script=${2:-e2e}  # e2e (painting), e2e_paint (painting over a clipping base), e2e_shafts (light shafts), e2e_tf (TF authoring), e2e_layout (the layout), e2e_undo (Undo and Redo), e2e_frame (framing an uploaded VDB) or e2e_api (the API page)
exec bash "$root/tests/web/with_server.sh" "$1" \
  env NODE_PATH="$modules" node "$root/tests/web/$script.cjs" "@URL@" "$root/build/test-artifacts/$script.png"
