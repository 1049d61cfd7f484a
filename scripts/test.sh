#!/usr/bin/env bash
# The whole suite: installs what is missing, builds, runs every test through CTest
# (ending with CTest's summary line).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
cd build
ctest --output-on-failure -j2 --timeout 900
