#!/usr/bin/env bash
# Regenerates docs/images/blender_panel.png: the Blender add-on's sidebar in a real Blender window
# under Xvfb (apt install xvfb xauth; not needed by the build or the tests).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
command -v xvfb-run >/dev/null || { echo "needs xvfb-run: apt install xvfb xauth"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
zip=$(bash "$root/clients/blender/build_addon.sh" "$work/volstyle_blender.zip")
export BLENDER_USER_CONFIG="$work/config" BLENDER_USER_SCRIPTS="$work/scripts"
blender -b --factory-startup -noaudio --python-expr "import bpy; bpy.ops.wm.save_as_mainfile(filepath='$work/start.blend')" >/dev/null
# Opening a file skips the splash; event simulation clicks the sidebar's tab.
bash "$root/tests/web/with_server.sh" "$root/build/bin/volstyle" \
  xvfb-run -a -s "-screen 0 1400x860x24" blender "$work/start.blend" --enable-event-simulate -noaudio \
  -P "$root/tests/blender/panel_screenshot.py" -- "$zip" "$root/docs/images/blender_panel.png"
