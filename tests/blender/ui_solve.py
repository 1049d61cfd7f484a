# The Solve button as an artist presses it (issue #38): in a real Blender window (under Xvfb), the
# modal solve follows the job in a thread and shows its progress in the status bar, then imports
# the result, and EEVEE renders the imported volume. Run by run_with_addon.sh under xvfb-run (CTest blender_ui):
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
scene.render.resolution_x = scene.render.resolution_y = 64
scene.volstyle.builtin_resolution, scene.volstyle.iterations = 32, 60
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
        ok = bool(seen) and imported.startswith("volstyle v")  # a fast solve may show only some of its phases
        print(f"UI SOLVE: the status bar showed {len(seen)} texts, e.g. {seen[:3]}; {scene.volstyle.status}; imported {imported}")
        ok = eevee_sees_it() and ok
        print("UI SOLVE: PASS" if ok else "UI SOLVE: FAIL")
        bpy.ops.wm.quit_blender()
        return None
    return 0.1


def eevee_sees_it():
    """The imported volume through the add-on's material in EEVEE (a window's GL context): it
    renders, and its light and coverage, part by part, are printed beside volstyle's. Measured,
    not held: under Xvfb on Mesa llvmpipe, EEVEE 3.4 fills the volume's whole box (Principled
    Volume does the same), so its figures say nothing of the material here."""
    from volstyle_blender import convert, material
    from volstyle_blender.volstyle_client import read_exr

    scene.render.engine, scene.render.film_transparent = "BLENDER_EEVEE", True
    scene.eevee.volumetric_tile_size, scene.eevee.use_volumetric_shadows = "2", True
    scene.eevee.volumetric_start, scene.eevee.volumetric_end = 0.5, 20.0
    os.makedirs(args[1], exist_ok=True)
    s = scene.render.image_settings
    s.file_format, s.color_depth = "OPEN_EXR", "32"
    vs, sid = session.client(scene), scene.volstyle.session
    _, _, ours = read_exr(vs.render(sid, convert.camera(scene, scene.camera), "exr", exr_type="float"))
    volume = scene.volstyle.volume_object
    grids = session.grids_of(volume.data)
    ok = True
    for part, emission, scattering in (("scattering", False, True), ("emission", True, False)):
        volume.data.materials[0] = material.volume_material(f"eevee {part}", grids, 0.0, emission, scattering)
        for o in scene.objects:
            if o.type == "LIGHT":
                o.hide_render = part == "emission"
        scene.render.filepath = os.path.join(args[1], f"eevee_{part}.exr")
        bpy.ops.render.render(write_still=True)
        with open(scene.render.filepath, "rb") as f:
            _, _, c = read_exr(f.read())
        theirs = sum(sum(c[k]) for k in "RGB")
        mine = sum(sum(ours[f"{part}.{k}"]) for k in "RGB")
        print(f"[ measured ] EEVEE {part}: medium light {theirs:.4g} against volstyle's {mine:.4g} (ratio {theirs / mine:.3f}), "
              f"coverage {sum(c['A']):.4g} against {sum(ours['A']):.4g}")
        ok = ok and theirs > 0 and sum(c["A"]) > 0
    return ok


bpy.app.timers.register(press_solve, first_interval=1.0)
