#!/usr/bin/env bash
# The whole suite: installs what is missing, builds, runs every test through CTest (ending with
# CTest's summary line).
#   scripts/test.sh                              the Release build in build/ (what CI runs), after the
#                                                parsers' fuzz corpus replayed under ASan+UBSan
#   scripts/test.sh --sanitize=address,undefined the suite under ASan+UBSan, in build-sanitize-address,undefined/
#   scripts/test.sh --sanitize=thread            under TSan, in build-sanitize-thread/
set -euo pipefail
cd "$(dirname "$0")/.."
sanitize=""
for arg in "$@"; do
  case "$arg" in
    --sanitize=*) sanitize="${arg#--sanitize=}" ;;
    *) echo "usage: scripts/test.sh [--sanitize=address,undefined|thread]" >&2; exit 2 ;;
  esac
done
bash scripts/install_deps.sh
build=build
if [ -n "$sanitize" ]; then
  build="build-sanitize-$sanitize"
  export VOLSTYLE_BUILD_DIR="$build"
  # Mesa's llvmpipe is not instrumented: leaks and races inside the driver are not ours to report.
  export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1:${ASAN_OPTIONS:-}"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$PWD/tests/sanitizers/ubsan.supp:${UBSAN_OPTIONS:-}"
  export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:history_size=7:suppressions=$PWD/tests/sanitizers/tsan.supp:${TSAN_OPTIONS:-}"
  bash scripts/build.sh "-DVOLSTYLE_SANITIZE=$sanitize"
else
  bash scripts/build.sh
fi
# playwright-core (browser test; the browser is Debian's chromium), ajv (schema test) and
# @seriousme/openapi-schema-validator (the OpenAPI description). Without the npm registry those
# tests skip rather than fail.
if [ ! -d build/web-test/node_modules/playwright-core ] || [ ! -d build/web-test/node_modules/ajv ] ||
   [ ! -d build/web-test/node_modules/@seriousme/openapi-schema-validator ]; then
  mkdir -p build/web-test
  (cd build/web-test && npm install --no-save --no-audit --no-fund playwright-core@1.65.1 ajv@8.20.0 \
     @seriousme/openapi-schema-validator@2.11.0) ||
    echo "test.sh: could not install playwright-core/ajv/openapi-schema-validator; the browser and schema tests will be skipped" >&2
fi
if [ -z "$sanitize" ]; then
  # The sanitizer variant CI runs (issue #9; the whole suite under ASan takes ~25 min to build
  # here): the parsers at the door — request validation, query strings, image and VDB decoding —
  # built with ASan+UBSan at -O1 and the fuzz corpus replayed through them. 4–6 min from scratch.
  VOLSTYLE_BUILD_DIR=build-asan-parsers bash scripts/build.sh -DVOLSTYLE_SANITIZE=address,undefined \
    -DVOLSTYLE_PARSERS_ONLY=ON -DCMAKE_CXX_FLAGS_RELEASE=-O1
  (cd build-asan-parsers &&
    ASAN_OPTIONS="detect_leaks=0:abort_on_error=1" \
    UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$PWD/../tests/sanitizers/ubsan.supp" \
    ctest --output-on-failure -j2 --timeout 600)
fi
cd "$build"
ctest --output-on-failure -j2 --timeout 900
