#!/usr/bin/env bash
# The Blender add-on against a live server (addon_test.py): builds the zip, runs Blender headless
# with a throw-away user folder (the add-on installs there, not in ~/.config).
# Usage: run_addon_test.sh VOLSTYLE_BINARY
set -euo pipefail
binary=$(realpath "$1")
root=$(cd "$(dirname "$0")/../.." && pwd)
command -v blender >/dev/null || { echo "needs Blender (scripts/install_deps.sh installs Debian's)"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
zip=$(bash "$root/clients/blender/build_addon.sh" "$work/volstyle_blender.zip")
export BLENDER_USER_CONFIG="$work/config" BLENDER_USER_SCRIPTS="$work/scripts"
bash "$root/tests/web/with_server.sh" "$binary" \
  blender -b --factory-startup -noaudio -P "$root/tests/blender/addon_test.py" -- "$zip" "$work/files" 2>&1 |
  grep -v "^Read blend\|^Blender quit\|^$" | tee "$work/out.txt"
grep -q "ADDON TEST: PASS" "$work/out.txt"
