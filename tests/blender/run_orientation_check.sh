#!/usr/bin/env bash
# The lat-long orientation against a real Blender render (orientation_check.py). Debian's Blender
# is installed by scripts/install_deps.sh (for this and the add-on's tests): without it, this fails.
set -euo pipefail
command -v blender >/dev/null || { echo "needs Blender (scripts/install_deps.sh installs Debian's)"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
here=$(cd "$(dirname "$0")" && pwd)
blender -b --factory-startup -P "$here/orientation_check.py" -- "$1" "$work" 2>&1 |
  grep -E "volstyle renders|Blender, Mapping|ORIENTATION CHECK" | tee "$work/out.txt"
grep -q "ORIENTATION CHECK: PASS" "$work/out.txt"
