# The Blender add-on end to end, inside Blender against a live server ($VOLSTYLE_URL):
#   tests/blender/run_with_addon.sh BINARY addon_test.py "ADDON TEST"  (blender -b … -P addon_test.py -- ADDON.zip WORKDIR)
# Installs the zip, builds a scene (an artist's VDB as a Volume object, moved and stood up; two
# cameras; a sun; a world colour), checks the camera conversion against Blender's own projection
# (ten points each, 0.5 px), then runs the operators: send the volume, render the views, paint one
# (a glow, an erased corner), send the paintings, solve, import; the imported object's VDB is the
# server's download and its grids are the session's. Prints "ADDON TEST: PASS" or exits 1.
import os
import random
import re
import subprocess
import sys
import traceback

import bpy
from bpy_extras.object_utils import world_to_camera_view
from mathutils import Matrix, Vector

args = sys.argv[sys.argv.index("--") + 1:]
zip_path, work = args[0], args[1]
os.makedirs(work, exist_ok=True)
checks = []


def check(ok, message):
    checks.append(message)
    if not ok:
        raise AssertionError(message)
    print("  ok:", message)


def scene_with_volume(vs):
    """The artist's scene: a VDB (a 24³ cloud written by the server) as a Volume object stood up,
    moved and turned a little; cameras A and B; a sun; a dark blue world."""
    scene = bpy.context.scene
    session = vs.create_session("builtin:cloud", 24)
    path = os.path.join(work, "artist_cloud.vdb")
    vs.download_volume(session["id"], path=path)
    vs.delete_session(session["id"])
    volume = bpy.data.volumes.new("cloud")
    volume.filepath = path
    obj = bpy.data.objects.new("cloud", volume)
    scene.collection.objects.link(obj)
    obj.matrix_world = Matrix.Translation((1.0, 2.0, 0.5)) @ Matrix.Rotation(0.3, 4, "Z") @ Matrix.Rotation(1.5707963, 4, "X")
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    centre = obj.matrix_world @ Vector((0, 0, 0))
    for name, offset, fit in (("Cam.A", (0.3, -3.6, 0.6), "AUTO"), ("Cam.B", (3.2, -1.2, 1.4), "VERTICAL")):
        cam = bpy.data.objects.new(name, bpy.data.cameras.new(name))
        scene.collection.objects.link(cam)
        cam.location = centre + Vector(offset)
        cam.rotation_euler = (centre - cam.location).to_track_quat("-Z", "Y").to_euler()
        cam.data.lens, cam.data.sensor_fit = 40, fit
    scene.camera = bpy.data.objects["Cam.A"]
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    scene.collection.objects.link(sun)
    sun.rotation_euler = (0.6, 0.2, 0.8)
    sun.data.energy, sun.data.color = 4.0, (1.0, 0.95, 0.85)
    scene.world = bpy.data.worlds.new("World")
    scene.world.color = (0.05, 0.07, 0.1)
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 64, 48, 100
    bpy.context.view_layer.update()  # the new locations into matrix_world
    return obj


def main():
    bpy.ops.wm.read_factory_settings(use_empty=True)  # before the add-on: it would unload it
    bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
    bpy.ops.preferences.addon_enable(module="volstyle_blender")
    from volstyle_blender import convert, session
    from volstyle_blender.volstyle_client import Client, project

    vs = Client(os.environ["VOLSTYLE_URL"])
    obj = scene_with_volume(vs)
    scene = bpy.context.scene
    scene.volstyle.url = os.environ["VOLSTYLE_URL"]
    check(bpy.ops.volstyle.connect() == {"FINISHED"}, f"connected: {scene.volstyle.status}")

    # The camera round trip: the volstyle camera puts ten world points where Blender does.
    scene.volstyle.volume_object = obj
    rng = random.Random(3)
    for cam in (bpy.data.objects["Cam.A"], bpy.data.objects["Cam.B"]):
        vcam = convert.camera(scene, cam)
        check(Vector(vcam["eye"]).length > 1.0, f"{cam.name} stands away from the volume's centre")
        to_vs = Matrix(convert.to_volstyle(scene))
        worst = 0.0
        for _ in range(10):
            p = obj.matrix_world @ Vector([rng.uniform(-0.8, 0.8) for _ in range(3)])
            u, v, _ = world_to_camera_view(scene, cam, p)
            px, py = project(vcam, list(to_vs @ p))
            worst = max(worst, abs(px - u * vcam["width"]), abs(py - (1 - v) * vcam["height"]))
        print(f"[ measured ] {cam.name} ({cam.data.sensor_fit}): ten points within {worst:.2e} px of Blender's projection")
        check(worst <= 0.5, f"{cam.name}: the projections agree to 0.5 px (worst {worst:.3g})")

    # The operators, as an artist presses them.
    check(bpy.ops.volstyle.send_volume(builtin=False) == {"FINISHED"}, f"send volume: {scene.volstyle.status}")
    sid = scene.volstyle.session
    check(vs.get_session(sid)["volume"]["dims"] == [24, 24, 24], "the session holds the artist's VDB")
    check(bpy.ops.volstyle.render_views() == {"FINISHED"}, f"render views: {scene.volstyle.status}")
    images = {i["volstyle_camera"]: i for i in session.painted_images(scene)}
    check(sorted(images) == ["Cam.A", "Cam.B"] and tuple(images["Cam.A"].size) == (64, 48), "an Image per camera, the render's size")
    # Paint Cam.A: a warm glow in the middle, an erased corner (alpha 0: asks nothing).
    image = images["Cam.A"]
    w, h = image.size
    px = list(image.pixels)
    for y in range(h):
        for x in range(w):
            i = 4 * (y * w + x)
            if (x - 32) ** 2 + (y - 24) ** 2 < 100:
                px[i:i + 3] = [px[i] * 1.5 + 0.15, px[i + 1] * 1.1 + 0.03, px[i + 2] * 0.8]
            if x < 6 and y > h - 6:
                px[i + 3] = 0.0
    image.pixels.foreach_set(px)
    exr, painted = session.target_of(image, keep_rest=True)
    check(painted >= 300, f"{painted} pixels count as painted (the glow and the erased corner)")
    check(bpy.ops.volstyle.send_targets() == {"FINISHED"}, f"send paintings: {scene.volstyle.status}")
    check(all(v["has_target"] and v["clipped_pixels"] == 0 for v in vs.list_views(sid)), "each view has a float target")

    scene.volstyle.iterations = 15
    before = vs.get_session(sid)["volume"]["version"]
    check(bpy.ops.volstyle.solve() == {"FINISHED"}, f"solve: {scene.volstyle.status}")
    info = vs.get_session(sid)
    version = info["volume"]["version"]
    check(version == before + 1, f"the solve made version {before + 1}")
    result = scene.volstyle.volume_object
    check(result is not None and result.name.startswith(f"volstyle v{version}"), f"imported as {result and result.name}")
    with open(bpy.path.abspath(result.data.filepath), "rb") as f:
        check(f.read() == vs.download_volume(sid), "the imported VDB is the server's download, byte for byte")
    grids = session.grids_of(result.data)
    listed = subprocess.run([os.environ["VOLSTYLE_BINARY"], "info", bpy.path.abspath(result.data.filepath)], capture_output=True,
                            text=True).stdout
    in_file = dict(re.findall(r"^  (\S+) +(float|vec3s)", listed, re.M))
    check({n: ("FLOAT" if t == "float" else "VECTOR_FLOAT") for n, t in in_file.items()} == grids,
          f"Blender reads the file's grids {grids} (volstyle info: {in_file})")
    check("emission" in grids, "the solve wrote emission")
    check(result.matrix_world == obj.matrix_world, "the result sits where the sent volume was")
    check(obj.hide_render and not result.hide_render, "the result replaces the sent volume in renders")
    # Light shafts: a wall with a window between the sun and the camera, sent to the stylizer.
    bpy.ops.mesh.primitive_plane_add(size=3, location=obj.matrix_world @ Vector((0, 0, 0)) + Vector((0, 1.5, 0)), rotation=(1.5708, 0, 0))
    bpy.ops.mesh.primitive_cube_add(size=0.6, location=obj.matrix_world @ Vector((0, 0, 0)) + Vector((0.8, 0.2, 0.3)))
    check(bpy.ops.volstyle.shafts() == {"FINISHED"}, f"light shafts: {scene.volstyle.status}")
    shafts = bpy.data.images.get("volstyle shafts")
    cam = convert.camera(scene, scene.camera)
    check(shafts is not None and tuple(shafts.size) == (cam["width"], cam["height"]), "the stylizer's frame is an Image of the camera's size")
    names = sorted(o["name"] for o in vs.list_occluders(sid))
    check(names == ["Cube", "Plane"], f"the meshes went as occluders {names}")
    frame = list(shafts.pixels)
    check(max(frame[i] for i in range(0, len(frame), 4)) > 0.0, "the frame is not black")
    print(f"ADDON TEST: PASS ({len(checks)} checks)")


try:
    main()
except Exception:
    traceback.print_exc()
    print(f"ADDON TEST: FAIL after {len(checks)} checks")
    sys.exit(1)
