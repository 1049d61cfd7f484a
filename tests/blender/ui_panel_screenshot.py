# docs/images/blender_panel.png: the add-on's sidebar tab in a real Blender window (under Xvfb),
# after sending the built-in cloud and rendering a view. Run by scripts/blender_screenshot.sh:
#   tests/blender/run_with_addon.sh BINARY ui_panel_screenshot.py SCREENSHOT OUT.png
import os
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1:]
zip_path, out = args[0], args[2]
bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
bpy.ops.preferences.addon_enable(module="volstyle_blender")
from volstyle_blender import session  # noqa: E402

scene = bpy.context.scene
for o in list(scene.objects):
    if o.type == "MESH":
        bpy.data.objects.remove(o)
scene.volstyle.url = os.environ["VOLSTYLE_URL"]
scene.render.resolution_x = scene.render.resolution_y = 128
scene.volstyle.builtin_resolution = 48
for o in list(scene.objects):
    if o.type == "LIGHT":
        o.data.type = "SUN"  # volstyle lights with suns: the factory lamp becomes one
        o.data.energy = 4.0
session.connect(scene)
session.send_volume(scene, builtin=True)
session.render_views(scene)


def shoot():
    win = bpy.context.window_manager.windows[0]
    area = next(a for a in win.screen.areas if a.type == "VIEW_3D")
    space = area.spaces.active
    space.show_region_ui = True
    space.shading.type = "MATERIAL"
    cloud = scene.volstyle.volume_object
    for o in scene.objects:
        o.select_set(o == cloud)
    bpy.context.view_layer.objects.active = cloud
    space.region_3d.view_location = (0.0, 0.0, 0.0)
    space.region_3d.view_distance = 5.5
    bpy.app.timers.register(lambda: click_tab(win, area), first_interval=1.5)
    return None


def click_tab(win, area):
    """The sidebar's 'volstyle' tab: Blender 3.4 has no API to pick a sidebar category, so click
    it (Blender runs with --enable-event-simulate): the tabs run down the region's right edge."""
    ui = next(r for r in area.regions if r.type == "UI")
    x = ui.x + ui.width - 10
    for y in range(ui.y + ui.height - 30, ui.y + ui.height - 400, -6):  # down the tab strip until our panel shows
        win.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
    win.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=TAB_Y(ui))
    win.event_simulate(type="LEFTMOUSE", value="PRESS", x=x, y=TAB_Y(ui))
    win.event_simulate(type="LEFTMOUSE", value="RELEASE", x=x, y=TAB_Y(ui))
    bpy.app.timers.register(lambda: capture(win), first_interval=3.0)
    return None


def TAB_Y(ui):
    # Tool, View, volstyle: about 50 px a tab from the top of the strip at Blender's default scale.
    return ui.y + ui.height - int(os.environ.get("TAB_OFFSET", "150"))


def capture(win):
    with bpy.context.temp_override(window=win):
        bpy.ops.screen.screenshot(filepath=out)
    print("SCREENSHOT: PASS", out)
    bpy.ops.wm.quit_blender()
    return None


bpy.app.timers.register(shoot, first_interval=2.0)
