# The Solve button as an artist presses it (issue #38): in a real Blender window (under Xvfb), the
# modal solve follows the job in a thread and shows its progress in the status bar, then imports
# the result. Run by run_with_addon.sh under xvfb-run (CTest blender_ui):
#   blender start.blend -P tests/blender/ui_solve.py -- ADDON.zip WORKDIR
import os
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1:]
zip_path = args[0]
bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
bpy.ops.preferences.addon_enable(module="volstyle_blender")
from volstyle_blender import session  # noqa: E402

scene = bpy.context.scene
scene.volstyle.url = os.environ["VOLSTYLE_URL"]
scene.render.resolution_x = scene.render.resolution_y = 48
scene.volstyle.builtin_resolution, scene.volstyle.iterations = 24, 25
for o in scene.objects:
    if o.type == "LIGHT":
        o.data.type = "SUN"
session.send_volume(scene, builtin=True)
image = session.render_views(scene)[0]
px = list(image.pixels)
image.pixels.foreach_set([v * 1.4 if i % 4 == 0 else v for i, v in enumerate(px)])  # a warmer view
session.send_targets(scene)
seen = []


def press_solve():
    win = bpy.context.window_manager.windows[0]
    area = next(a for a in win.screen.areas if a.type == "VIEW_3D")
    with bpy.context.temp_override(window=win, area=area):
        result = bpy.ops.volstyle.solve("INVOKE_DEFAULT")
    print("UI SOLVE: invoked", result)
    bpy.app.timers.register(watch, first_interval=0.2)


def watch():
    text = scene.volstyle.get("progress", "")
    if text and (not seen or seen[-1] != text):
        seen.append(text)
    if scene.volstyle.status.startswith("solved") or len(seen) > 10000:
        imported = scene.volstyle.volume_object.name
        ok = any("iterating" in t for t in seen) and imported.startswith("volstyle v")
        print(f"UI SOLVE: the status bar showed {len(seen)} texts, e.g. {seen[:3]}; {scene.volstyle.status}; imported {imported}")
        print("UI SOLVE: PASS" if ok else "UI SOLVE: FAIL")
        bpy.ops.wm.quit_blender()
        return None
    return 0.1


bpy.app.timers.register(press_solve, first_interval=1.0)
