# The lat-long convention against Blender (docs/LIGHTING.md, "Orientation"): run inside Blender,
#   blender -b --factory-startup -P tests/blender/orientation_check.py -- VOLSTYLE_BINARY WORKDIR
# It writes a lat-long map whose six regions (the dominant axis of each direction, in volstyle's
# convention) have six colours, renders it with volstyle as the background looking along ±x, ±y,
# ±z, then renders it in Blender as the world's Environment Texture with the documented set-up
# (volstyle's +y-up world turned +z-up: (x, y, z) -> (x, -z, y); Mapping rotation z = 270°, i.e. −90°) looking
# along the same directions, and checks that both see the region of each direction. Other mapping
# rotations are tried too and reported, so a wrong claim shows which one is right. Exit code 1 on a
# mismatch.
import math
import os
import subprocess
import sys

import bpy
from mathutils import Vector

args = sys.argv[sys.argv.index("--") + 1:]
volstyle, work = args[0], args[1]
os.makedirs(work, exist_ok=True)

# The six regions: the dominant axis of a direction, and its colour.
# Each axis tilted a little (the poles are singular for a lat-long lookup: Blender blends there).
AXES = {"+x": (1, 0.2, 0.1), "-x": (-1, 0.1, -0.2), "+y": (0.2, 1, 0.1), "-y": (0.1, -1, -0.2), "+z": (0.2, 0.1, 1), "-z": (-0.1, 0.2, -1)}
COLOURS = {"+x": (1, 0, 0), "-x": (0, 1, 1), "+y": (0, 1, 0), "-y": (1, 0, 1), "+z": (0, 0, 1), "-z": (1, 1, 0)}


def region(d):
    i = max(range(3), key=lambda k: abs(d[k]))
    return ("+" if d[i] > 0 else "-") + "xyz"[i]


def region_of_colour(rgb):
    bits = tuple(1 if c > 0.5 else 0 for c in rgb[:3])
    for name, c in COLOURS.items():
        if c == bits:
            return name
    return "?" + str(bits)


# volstyle's lat-long convention (core/scene/environment_lobes.h): u = 0.5 + atan2(x, -z)/2π, v = acos(y)/π,
# v = 0 the top row; so a texel (u, v) looks along this direction.
def lat_long_direction(u, v):
    phi = (u - 0.5) * 2 * math.pi
    theta = v * math.pi
    return (math.sin(theta) * math.sin(phi), math.cos(theta), -math.sin(theta) * math.cos(phi))


W, H = 256, 128
img = bpy.data.images.new("dirs", W, H, float_buffer=True, alpha=True)
pixels = [0.0] * (W * H * 4)
for row_from_top in range(H):
    for x in range(W):
        d = lat_long_direction((x + 0.5) / W, (row_from_top + 0.5) / H)
        c = COLOURS[region(d)]
        i = ((H - 1 - row_from_top) * W + x) * 4  # Blender stores rows bottom-up
        pixels[i:i + 4] = [float(c[0]), float(c[1]), float(c[2]), 1.0]
img.pixels = pixels
map_path = os.path.join(work, "dirs.exr")
img.filepath_raw = map_path
img.file_format = "OPEN_EXR"
img.save()


def centre_colour(path):
    im = bpy.data.images.load(path)
    w, h = im.size
    px = list(im.pixels)
    i = ((h // 2) * w + w // 2) * 4
    out = px[i:i + 3]
    bpy.data.images.remove(im)
    return out


# volstyle, looking along each axis from outside the volume (background only).
with open(os.path.join(work, "lighting.json"), "w") as f:
    f.write('{"background": {"environment": "dirs.exr"}}')
volstyle_sees = {}
for name, d in AXES.items():
    up = (1, 0, 0) if name in ("+y", "-y") else (0, 1, 0)  # not along the view
    eye = tuple(5 * c for c in d)
    target = tuple(6 * c for c in d)
    cam = os.path.join(work, "camera_%s.json" % name.replace("+", "p").replace("-", "m"))
    with open(cam, "w") as f:
        f.write('{"eye": %s, "target": %s, "up": %s, "fov_y_deg": 2, "width": 8, "height": 8}' % (list(eye), list(target), list(up)))
    out = os.path.join(work, "volstyle_%s.png" % name.replace("+", "p").replace("-", "m"))
    subprocess.run([volstyle, "render", "--scene", "builtin:sphere:8", "--camera", cam, "--lighting",
                    os.path.join(work, "lighting.json"), "-o", out], check=True, capture_output=True)
    volstyle_sees[name] = region_of_colour(centre_colour(out))

# Blender: the world's Environment Texture through a Mapping node (rotation about z).
scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.samples = 1
scene.cycles.use_denoising = False
scene.render.resolution_x = scene.render.resolution_y = 8
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "PNG"
scene.view_settings.view_transform = "Standard"
for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)
cam_data = bpy.data.cameras.new("cam")
cam_data.angle = math.radians(2)
camera = bpy.data.objects.new("cam", cam_data)
scene.collection.objects.link(camera)
scene.camera = camera
world = bpy.data.worlds.new("world")
scene.world = world
world.use_nodes = True
nodes, links = world.node_tree.nodes, world.node_tree.links
nodes.clear()
coords = nodes.new("ShaderNodeTexCoord")
mapping = nodes.new("ShaderNodeMapping")
env = nodes.new("ShaderNodeTexEnvironment")
env.image = bpy.data.images.load(map_path)
background = nodes.new("ShaderNodeBackground")
output = nodes.new("ShaderNodeOutputWorld")
links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
links.new(mapping.outputs["Vector"], env.inputs["Vector"])
links.new(env.outputs["Color"], background.inputs["Color"])
links.new(background.outputs["Background"], output.inputs["Surface"])


def blender_sees(rotation_z_deg):
    mapping.inputs["Rotation"].default_value = (0, 0, math.radians(rotation_z_deg))
    seen = {}
    for name, d in AXES.items():
        db = Vector((d[0], -d[2], d[1])).normalized()  # volstyle +y up -> Blender +z up (+90° about x)
        camera.rotation_mode = "QUATERNION"
        camera.rotation_quaternion = db.to_track_quat("-Z", "Y" if abs(db.z) > 0.5 else "Z")
        out = os.path.join(work, "blender_%d_%s.png" % (rotation_z_deg, name.replace("+", "p").replace("-", "m")))
        scene.render.filepath = out
        bpy.ops.render.render(write_still=True)
        seen[name] = region_of_colour(centre_colour(out))
    return seen


ok_volstyle = all(volstyle_sees[n] == n for n in AXES)
print("volstyle renders the map as its convention says:", "yes" if ok_volstyle else "NO", volstyle_sees)
documented = 270
results = {}
for rot in (0, 90, 180, 270):
    seen = blender_sees(rot)
    results[rot] = all(seen[n] == n for n in AXES)
    print("Blender, Mapping rotation z = %3d°: %s %s" % (rot, "matches" if results[rot] else "differs", seen))
ok = ok_volstyle and results[documented]
print("ORIENTATION CHECK:", "PASS" if ok else "FAIL", "(documented: rotation z = %d°)" % documented)
sys.exit(0 if ok else 1)
