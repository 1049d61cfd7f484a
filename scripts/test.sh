#!/usr/bin/env bash
# The whole suite: installs what is missing, builds, runs every test through CTest
# (ending with CTest's summary line).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
# playwright-core for the browser test (the browser itself is Debian's chromium). Without the npm
# registry the test skips rather than fails.
if [ ! -d build/web-test/node_modules/playwright-core ]; then
  mkdir -p build/web-test
  (cd build/web-test && npm install --no-save --no-audit --no-fund playwright-core@1.65.1) ||
    echo "test.sh: could not install playwright-core; the browser test will be skipped" >&2
fi
cd build
ctest --output-on-failure -j2 --timeout 900
