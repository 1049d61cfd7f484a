#!/usr/bin/env bash
# The whole suite: installs what is missing, builds, runs every test through CTest
# (ending with CTest's summary line).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
# playwright-core (browser test; the browser is Debian's chromium) and ajv (schema test). Without
# the npm registry those tests skip rather than fail.
if [ ! -d build/web-test/node_modules/playwright-core ] || [ ! -d build/web-test/node_modules/ajv ]; then
  mkdir -p build/web-test
  (cd build/web-test && npm install --no-save --no-audit --no-fund playwright-core@1.65.1 ajv@8.20.0) ||
    echo "test.sh: could not install playwright-core/ajv; the browser and schema tests will be skipped" >&2
fi
cd build
ctest --output-on-failure -j2 --timeout 900
