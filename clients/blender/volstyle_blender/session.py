"""The add-on's work, as plain functions of a scene (the operators call them; scripts and tests
may too): connect, send a volume, render views into Images, send the paintings, solve, import."""
from __future__ import annotations

import os
import re
import tempfile

import bpy

from . import convert, material, pixels
from .volstyle_client import BLENDER_FROM_VOLSTYLE, Client, exr_rgba, picture_of, read_exr

VIEW_KEY, SESSION_KEY, BASE_PREFIX = "volstyle_view", "volstyle_session", "volstyle base "


def token() -> str | None:
    """The server's token: the add-on's preferences (kept with Blender's preferences, never in a
    .blend), else $VOLSTYLE_TOKEN."""
    addon = bpy.context.preferences.addons.get(__package__)
    value = addon.preferences.token if addon and hasattr(addon.preferences, "token") else ""
    return value or None


def client(scene) -> Client:
    return Client(scene.volstyle.url, token())


def require_session(scene) -> str:
    if not scene.volstyle.session:
        raise ValueError("send a volume first (volstyle ▸ Send volume)")
    return scene.volstyle.session


def files_folder() -> str:
    """Where downloaded VDBs go: //volstyle/ beside the .blend, or a temporary folder if unsaved."""
    folder = bpy.path.abspath("//volstyle") if bpy.data.filepath else os.path.join(tempfile.gettempdir(), "volstyle")
    os.makedirs(folder, exist_ok=True)
    return folder


def connect(scene) -> dict:
    health = client(scene).health()
    scene.volstyle.status = f"connected: {health.get('gl_renderer', 'server')}"
    return health


def grids_of(volume) -> dict:
    """A Volume's grids as the file has them: {name: data_type}."""
    volume.grids.load()
    return {g.name: g.data_type for g in volume.grids}


def import_vdb(scene, path: str, name: str, matrix):
    """A Volume object reading `path`, placed by `matrix`, with the volstyle material."""
    volume = bpy.data.volumes.new(name)
    volume.filepath = path
    obj = bpy.data.objects.new(name, volume)
    scene.collection.objects.link(obj)
    obj.matrix_world = matrix
    volume.materials.append(material.volume_material(name, grids_of(volume), scene.volstyle.anisotropy))
    return obj


def send_volume(scene, obj=None, builtin: bool = False) -> dict:
    """Starts a session holding the selected Volume object's VDB (or a built-in cloud, imported
    upright: volstyle is y-up), and makes that object volstyle's space."""
    vs = client(scene)
    if builtin:
        session = vs.create_session("builtin:" + scene.volstyle.builtin_scene, scene.volstyle.builtin_resolution)
        path = os.path.join(files_folder(), f"{session['id']}_v1.vdb")
        vs.download_volume(session["id"], path=path)
        from mathutils import Matrix

        obj = import_vdb(scene, path, "volstyle " + scene.volstyle.builtin_scene, Matrix(BLENDER_FROM_VOLSTYLE))
    else:
        if obj is None or obj.type != "VOLUME":
            raise ValueError("select a Volume object (or send the built-in cloud)")
        path = bpy.path.abspath(obj.data.filepath)
        if not os.path.isfile(path):
            raise ValueError(f"{obj.name}: its VDB '{path}' is not a file on disk")
        session = vs.create_session("builtin:cloud", 8)  # the smallest start, replaced at once
        try:
            session = vs.upload_volume(session["id"], path)
        except Exception:
            vs.delete_session(session["id"])
            raise
    scene.volstyle.session = session["id"]
    scene.volstyle.volume_object = obj
    send_lighting(scene)
    scene.volstyle.status = f"session {session['id'][:8]}: {obj.name}, {'×'.join(map(str, session['volume']['dims']))} voxels"
    return session


def send_lighting(scene) -> dict | None:
    """The scene's suns and world colour as the session's lighting; without a sun the session
    keeps volstyle's default lighting (a warm sun and a blue sky) and the status says so."""
    lighting = convert.lighting(scene)
    if lighting is None:
        scene.volstyle["lighting_note"] = "no sun lamp in the scene: volstyle's default lighting is used"
        return None
    scene.volstyle["lighting_note"] = ""
    return client(scene).set_lighting(require_session(scene), lighting)


def cameras(scene, selected_only: bool = False) -> list:
    objs = [o for o in scene.objects if o.type == "CAMERA" and (o.select_get() or not selected_only)]
    return sorted(objs, key=lambda o: o.name)


def render_views(scene, cams=None) -> list:
    """Each camera's view through the server, as a float Image 'volstyle CAMERA' to paint (and a
    hidden copy of it, what the painting started from). Returns the Images."""
    sid, vs = require_session(scene), client(scene)
    cams = cameras(scene) if cams is None else cams
    if not cams:
        raise ValueError("no camera to render: add one (or select one, with Selected cameras only)")
    send_lighting(scene)
    images = []
    for cam in cams:
        old = cam.get(VIEW_KEY)
        if old and cam.get(SESSION_KEY) == sid:
            try:
                vs.delete_view(sid, old)
            except Exception:  # already gone
                pass
        view = vs.add_view(sid, convert.camera(scene, cam))
        cam[VIEW_KEY], cam[SESSION_KEY] = view["id"], sid
        w, h, layers = read_exr(vs.render_view(sid, view["id"], "exr", exr_type="float"))
        picture = picture_of(layers)
        pixels.image_from_rgb(BASE_PREFIX + cam.name, w, h, picture, hidden=True)
        image = pixels.image_from_rgb("volstyle " + cam.name, w, h, picture)
        image[VIEW_KEY], image[SESSION_KEY], image["volstyle_camera"] = view["id"], sid, cam.name
        images.append(image)
    note = scene.volstyle.get("lighting_note") or ""
    scene.volstyle.status = f"{len(images)} views rendered: paint them (Texture Paint), then Send paintings" + (f" ({note})" if note else "")
    return images


def painted_images(scene) -> list:
    sid = scene.volstyle.session
    return [i for i in bpy.data.images if i.get(SESSION_KEY) == sid and i.get(VIEW_KEY) and not i.name.startswith(".")]


def target_of(image, keep_rest: bool) -> tuple[bytes, int]:
    """The painting as the solve's target (linear float EXR): RGB as painted; the weight is the
    image's alpha (Erase Alpha marks pixels that ask nothing) where the artist painted, and where
    not, 1 with Keep the rest (the view as it rendered) or 0."""
    w, h = image.size
    rgba = pixels.rgba_of(image)
    base_image = bpy.data.images.get("." + BASE_PREFIX + image["volstyle_camera"])
    base = pixels.rgba_of(base_image) if base_image else rgba
    rgb, weight, painted = [0.0] * (3 * w * h), [0.0] * (w * h), 0
    for i in range(w * h):
        p, b = rgba[4 * i:4 * i + 4], base[4 * i:4 * i + 3]
        rgb[3 * i:3 * i + 3] = p[:3]
        changed = any(abs(x - y) > 1e-6 * max(1.0, abs(y)) for x, y in zip(p[:3], b)) or p[3] < 1.0
        painted += changed
        weight[i] = max(0.0, min(1.0, p[3])) if changed else (1.0 if keep_rest else 0.0)
    return exr_rgba(w, h, rgb, weight), painted


def send_targets(scene) -> list:
    """Every painted view of this session to the server as its target; returns the views."""
    sid, vs = require_session(scene), client(scene)
    views = []
    for image in painted_images(scene):
        exr, painted = target_of(image, scene.volstyle.keep_rest)
        views.append(vs.set_target(sid, image[VIEW_KEY], exr))
        image["volstyle_painted_pixels"] = painted
    if not views:
        raise ValueError("no painted views: Render views first, then paint them")
    scene.volstyle.status = f"{len(views)} targets sent"
    return views


def solve_options(scene) -> dict:
    s = scene.volstyle
    return {"unknowns": s.unknowns.split(","), "max_iterations": s.iterations}


def import_result(scene, version: int | None = None):
    """The session's (current or given) version as a Volume object over the sent one."""
    sid, vs = require_session(scene), client(scene)
    info = vs.get_session(sid)
    version = version or info["volume"]["version"]
    path = os.path.join(files_folder(), f"{sid}_v{version}.vdb")
    vs.download_volume(sid, version, path=path)
    from mathutils import Matrix

    source = scene.volstyle.volume_object
    matrix = source.matrix_world.copy() if source else None
    obj = import_vdb(scene, path, f"volstyle v{version}", matrix if matrix is not None else Matrix.Identity(4))
    if source:
        source.hide_render = source.hide_viewport = True  # the result replaces it on screen
    scene.volstyle.volume_object = obj
    scene.volstyle.status = f"imported version {version}"
    return obj


def shafts(scene, width: int | None = None) -> object:
    """The scene's meshes and sun as a light-shaft stylizer scene; its frame as Image 'volstyle shafts'."""
    sid, vs = require_session(scene), client(scene)
    if scene.camera is None:
        raise ValueError("the scene has no active camera")
    sun = (convert.suns(scene) or [None])[0]
    if sun is None:
        raise ValueError("the scene has no sun lamp")
    occluders = []
    for obj in scene.objects:
        if obj.type == "MESH" and not obj.hide_render:
            name = re.sub(r"[^A-Za-z0-9_.-]", "_", obj.name)[:64]
            vs.upload_occluder(sid, name, convert.mesh_obj(scene, obj))
            colour = list(obj.active_material.diffuse_color[:3]) if obj.active_material else [0.4, 0.35, 0.3]
            occluders.append({"name": name, "mesh": name, "colour": [min(1.0, max(0.0, c)) for c in colour]})
    light = convert.lighting(scene)["lights"][0]  # a sun exists (checked above)
    cam = convert.camera(scene, scene.camera)
    if width:
        cam["height"], cam["width"] = max(1, round(cam["height"] * width / cam["width"])), width
    vs.set_stylizer(sid, {"occluders": occluders, "light": {"type": "directional", **light}, "camera": cam,
                          "background": convert.world_colour(scene)})
    w, h, layers = read_exr(vs.stylizer_frame(sid, {"format": "exr"}))
    image = pixels.image_from_rgb("volstyle shafts", w, h, [v for i in range(w * h) for v in (layers["R"][i], layers["G"][i], layers["B"][i])])
    scene.volstyle.status = f"light shafts: {len(occluders)} meshes"
    return image
