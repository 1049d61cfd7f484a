#!/usr/bin/env bash
# Runs a Blender test script with the add-on against a live server: builds the add-on zip, runs
# Blender headless with a throw-away user folder (the add-on installs there, not in ~/.config),
# passes `-- ZIP WORKDIR ARGS…` to the script and passes when it prints "NAME: PASS".
# Usage: run_with_addon.sh VOLSTYLE_BINARY SCRIPT.py NAME [ARGS…]
#   addon_test.py "ADDON TEST" — the operators end to end;
#   cycles_match.py "CYCLES MATCH" [SAMPLES [both]] — Cycles against volstyle (default 128 samples;
#     `both`: also the material with both parts, printed, not held);
#   ui_solve.py "UI SOLVE" — a script named ui_* runs in a real Blender window under Xvfb;
#   ui_panel_screenshot.py SCREENSHOT OUT.png — docs/images/blender_panel.png (scripts/blender_screenshot.sh).
set -euo pipefail
binary=$(realpath "$1")
script=$2
name=$3
shift 3
root=$(cd "$(dirname "$0")/../.." && pwd)
command -v blender >/dev/null || { echo "needs Blender (scripts/install_deps.sh installs Debian's)"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
zip=$(bash "$root/clients/blender/build_addon.sh" "$work/volstyle_blender.zip")
export BLENDER_USER_CONFIG="$work/config" BLENDER_USER_SCRIPTS="$work/scripts"
blender=(blender -b --factory-startup)
if [[ $script == ui_* ]]; then  # a window: Xvfb, and a saved file to open (a file skips the splash)
  command -v xvfb-run >/dev/null || { echo "needs xvfb-run (scripts/install_deps.sh installs xvfb)"; exit 1; }
  blender -b --factory-startup -noaudio --python-expr "import bpy; bpy.ops.wm.save_as_mainfile(filepath='$work/start.blend')" >/dev/null
  # Event simulation: a script may click what Blender has no API for (the sidebar's tab).
  blender=(xvfb-run -a -s "-screen 0 1400x860x24" blender "$work/start.blend" --enable-event-simulate)
fi
bash "$root/tests/web/with_server.sh" "$binary" \
  "${blender[@]}" -noaudio -P "$root/tests/blender/$script" -- "$zip" "$work/files" "$@" 2>&1 |
  grep -E "measured|  ok:|$name|Error|Traceback|^  File|^Warning" | tee "$work/out.txt" || true
grep -q "$name: PASS" "$work/out.txt"
