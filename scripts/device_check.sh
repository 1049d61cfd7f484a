#!/usr/bin/env bash
# Runs on a GPU machine, from the repository root, what scripts/device_bundle.sh packed: the GL
# tests (121, those that need no file libraries) and the stylizer and renderer benchmarks, on the
# EGL GPU device (VOLSTYLE_EGL=device unless set: a run that fell back to llvmpipe would prove
# nothing). Results go to $OUT (or device-out/): gl_tests.log, stylizer_bench.txt,
# render_bench.txt. Exit status 1 when a test fails, is skipped or ran on a software renderer.
# About 2 minutes on an H200. --tests-only skips the benchmarks; GTEST_FILTER picks tests.
set -uo pipefail
bundle="$(cd "$(dirname "$0")" && pwd)"
out="${OUT:-device-out}"
mkdir -p "$out"
# glvnd's loaders where the machine has the driver but no libEGL.so.1 (a bare CUDA image).
if ! grep -q 'libEGL\.so\.1 ' < <(ldconfig -p); then
  shopt -s nullglob
  debs=("$bundle"/deb/*.deb)
  if [ "${#debs[@]}" -eq 0 ] || [ "$(id -u)" -ne 0 ]; then
    echo "device_check: no libEGL.so.1 here, and its packages cannot be unpacked (none in the bundle, or not root)" >&2
    exit 1
  fi
  for f in "${debs[@]}"; do dpkg -x "$f" / || { echo "device_check: could not unpack $f" >&2; exit 1; }; done
  ldconfig
fi
export LD_LIBRARY_PATH="$bundle/lib:/usr/local/nvidia/lib64:/usr/local/nvidia/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
vendor=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
if [ -f "$vendor" ] && [ -z "${__EGL_VENDOR_LIBRARY_FILENAMES:-}" ]; then export __EGL_VENDOR_LIBRARY_FILENAMES="$vendor"; fi
export VOLSTYLE_EGL="${VOLSTYLE_EGL:-device}"

timeout 300 "$bundle/bin/gl_tests_device" > "$out/gl_tests.log" 2>&1
status=$?
grep -E "^\[ renderer \]|^\[  (PASSED|FAILED|SKIPPED) " "$out/gl_tests.log"
if grep -q "^\[  SKIPPED \]" "$out/gl_tests.log"; then echo "device_check: tests were skipped (no GL context?)" >&2; status=1; fi
if grep -qE "^\[ renderer \].*(llvmpipe|softpipe)" "$out/gl_tests.log"; then echo "device_check: ran on a software renderer" >&2; status=1; fi
[ "$status" -ne 0 ] && status=1
[ "${1:-}" = "--tests-only" ] && exit $status
timeout 180 "$bundle/bin/stylizer_bench" --reps 5 > "$out/stylizer_bench.txt" 2>&1 || echo "stylizer_bench failed ($?)"
grep -v '^{' "$out/stylizer_bench.txt" | head -12
# The live stream's read-back (issue #40): floats and a CPU conversion against GPU-packed bytes.
timeout 60 "$bundle/bin/stylizer_bench" --live > "$out/stylizer_live.txt" 2>&1 || echo "stylizer_bench --live failed ($?)"
cat "$out/stylizer_live.txt"
timeout 120 "$bundle/bin/render_bench" > "$out/render_bench.txt" 2>&1 || echo "render_bench failed ($?)"
exit $status
