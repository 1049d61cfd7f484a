#!/usr/bin/env bash
# Configures (once) and builds volstyle in Release into build/ (or $VOLSTYLE_BUILD_DIR). Used by
# run.sh and test.sh. Extra arguments go to the first CMake configure (e.g. -DVOLSTYLE_SANITIZE=thread).
set -euo pipefail
cd "$(dirname "$0")/.."
build="${VOLSTYLE_BUILD_DIR:-build}"
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "$@"
fi
cmake --build "$build" -j"$(nproc)"
