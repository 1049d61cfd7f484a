#!/usr/bin/env bash
# Runs on a GPU machine, from the repository root, what scripts/device_bundle.sh packed: the GL
# tests (121, those that need no file libraries) and the stylizer and renderer benchmarks, on the
# EGL GPU device. Results go to $OUT (or device-out/): gl_tests.log, stylizer_bench.txt,
# render_bench.txt. Exit status: the tests'. About 2 minutes on an H200. --tests-only skips the
# benchmarks; GTEST_FILTER picks tests (GoogleTest reads it).
set -uo pipefail
bundle="$(cd "$(dirname "$0")" && pwd)"
out="${OUT:-device-out}"
mkdir -p "$out"
# glvnd's loaders where the machine has the driver but no libEGL.so.1 (a bare CUDA image).
if ! ldconfig -p | grep -q 'libEGL.so.1 '; then
  for f in "$bundle"/deb/*.deb; do dpkg -x "$f" /; done
  ldconfig
fi
export LD_LIBRARY_PATH="$bundle/lib:/usr/local/nvidia/lib64:/usr/local/nvidia/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
vendor=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
if [ -f "$vendor" ] && [ -z "${__EGL_VENDOR_LIBRARY_FILENAMES:-}" ]; then export __EGL_VENDOR_LIBRARY_FILENAMES="$vendor"; fi
timeout 300 "$bundle/bin/gl_tests_device" > "$out/gl_tests.log" 2>&1
status=$?
grep -E "^\[ renderer \]|^\[  (PASSED|FAILED) " "$out/gl_tests.log"
[ "${1:-}" = "--tests-only" ] && exit $status
timeout 180 "$bundle/bin/stylizer_bench" --reps 5 > "$out/stylizer_bench.txt" 2>&1 || echo "stylizer_bench failed ($?)"
grep -v '^{' "$out/stylizer_bench.txt" | head -12
timeout 120 "$bundle/bin/render_bench" > "$out/render_bench.txt" 2>&1 || echo "render_bench failed ($?)"
exit $status
