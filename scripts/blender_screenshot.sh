#!/usr/bin/env bash
# Regenerates docs/images/blender_panel.png: the Blender add-on's sidebar in a real Blender window
# under Xvfb (tests/blender/ui_panel_screenshot.py, run as the add-on's window tests are).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/tests/blender/run_with_addon.sh" "$root/build/bin/volstyle" ui_panel_screenshot.py SCREENSHOT "$root/docs/images/blender_panel.png"
