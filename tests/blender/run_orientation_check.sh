#!/usr/bin/env bash
# The lat-long orientation against a real Blender render (orientation_check.py). Blender is not a
# dependency of volstyle: without it (`apt install blender` adds it) the test is skipped (77).
set -euo pipefail
if ! command -v blender >/dev/null; then
  echo "skipping: Blender is not installed (apt install blender, then run again)"
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
here=$(cd "$(dirname "$0")" && pwd)
blender -b --factory-startup -P "$here/orientation_check.py" -- "$1" "$work" 2>&1 |
  grep -E "volstyle renders|Blender, Mapping|ORIENTATION CHECK" | tee "$work/out.txt"
grep -q "ORIENTATION CHECK: PASS" "$work/out.txt"
