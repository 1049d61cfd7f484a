"""volstyle from Houdini: a shelf tool (or Python SOP) recipe on the volstyle Python client.

Install the client where Houdini's Python finds it (docs/CLIENTS.md):
    hython -m pip install /path/to/volstyle/clients/python      (or add it to PYTHONPATH)
then make a shelf tool whose script is:

    import volstyle_houdini as vh
    vh.shelf_tool(kwargs=kwargs)   # shift-click starts over

It does the steps in two clicks. First click (a File SOP reading the VDB selected): send the VDB
and the scene's distant lights, render each camera's view to $HIP/volstyle/<camera>.exr (paint it
in COPs, Nuke or Mari and save it as <camera>.painted.exr, alpha = weight). Second click: send
the paintings, solve (Cancel in Houdini's interrupt dialog cancels the job on the server), write
$HIP/volstyle/solved.vdb for a File SOP, and start over. Shift-click starts over at any time. The
session lives in this Houdini process (hou.session), not in the .hip file. Everything but
`shelf_tool` is plain Python on the client, tested without Houdini
(clients/houdini/tests/test_recipe.py)."""
from __future__ import annotations

import os
from typing import Iterable

import volstyle_client as vc


def houdini_camera(node) -> dict:
    """A volstyle camera from a Houdini camera object node (hou.ObjNode of type cam)."""
    ev = lambda name, default=None: node.parm(name).eval() if node.parm(name) is not None else default  # noqa: E731
    m = node.worldTransform()
    rows = [[m.at(i, j) for j in range(4)] for i in range(4)] if hasattr(m, "at") else m
    return vc.camera.camera_from_houdini(rows, focal=ev("focal"), aperture=ev("aperture"), resx=int(ev("resx")), resy=int(ev("resy")),
                                         aspect=ev("aspect", 1.0), win=(ev("winx", 0.0), ev("winy", 0.0)),
                                         clip=(ev("near", 0.001), ev("far", 10000.0)), perspective=ev("projection", 0) in (0, "perspective"))


def houdini_sun(node) -> dict:
    """A volstyle directional light from a Houdini distant light (shines down its −Z; irradiance
    = light_intensity · 2^light_exposure · light_color)."""
    m = node.worldTransform()
    rows = [[m.at(i, j) for j in range(4)] for i in range(4)] if hasattr(m, "at") else m
    column = [[float(rows[j][i]) for j in range(4)] for i in range(4)]
    colour = [node.parm(f"light_color{c}").eval() for c in "rgb"]
    strength = node.parm("light_intensity").eval() * 2.0 ** node.parm("light_exposure").eval()
    return vc.sun_from_dcc(column, strength, colour)


def send(vs: vc.Client, vdb_path: str, suns: Iterable[dict] = (), background=(0.0, 0.0, 0.0)) -> str:
    """A new session holding the VDB, lit by `suns` (none: volstyle's default lighting); its id."""
    sid = vs.create_session("builtin:cloud", 8)["id"]  # the smallest start, replaced at once
    try:
        vs.upload_volume(sid, vdb_path)
    except Exception:
        vs.delete_session(sid)  # no orphan session on the server
        raise
    suns = list(suns)
    if suns:
        vs.set_lighting(sid, {"lights": suns, "background": {"color": list(background)}})
    return sid


def render_views(vs: vc.Client, sid: str, cameras: dict, folder: str) -> dict:
    """Adds a view per camera ({name: volstyle camera}) and writes its linear render to
    FOLDER/<name>.exr (the picture: medium over background, float RGBA); {name: view id}."""
    os.makedirs(folder, exist_ok=True)
    views = {}
    for name, camera in cameras.items():
        view = vs.add_view(sid, camera)
        w, h, layers = vc.read_exr(vs.render_view(sid, view["id"], "exr", exr_type="float"))
        with open(os.path.join(folder, f"{name}.exr"), "wb") as f:
            f.write(vc.exr_rgba(w, h, vc.picture_of(layers), 1.0))
        views[name] = view["id"]
    return views


def send_paintings(vs: vc.Client, sid: str, views: dict, folder: str) -> list:
    """Every FOLDER/<name>.painted.exr as its view's target (alpha = weight); the names sent."""
    sent = []
    for name, vid in views.items():
        path = os.path.join(folder, f"{name}.painted.exr")
        if os.path.isfile(path):
            vs.set_target(sid, vid, path)
            sent.append(name)
    if not sent:
        raise ValueError(f"no <camera>.painted.exr in {folder}: paint the renders first")
    return sent


def solve_and_fetch(vs: vc.Client, sid: str, out_path: str, unknowns=("emission", "albedo"), iterations: int = 30, progress=None) -> dict:
    """Solves, writes the solved VDB to `out_path` (for a File SOP) and returns the job's result."""
    result = vs.solve(sid, unknowns=list(unknowns), max_iterations=iterations).wait(progress=progress)
    vs.download_volume(sid, path=out_path)
    return result


def shelf_tool(url: str | None = None, kwargs: dict | None = None, iterations: int = 30) -> None:  # pragma: no cover - needs Houdini
    """The shelf tool: one step per click (pass the shelf script's `kwargs`: shift-click starts
    over), remembered for this Houdini process in hou.session."""
    import hou

    vs = vc.Client(url or os.environ.get("VOLSTYLE_URL", "http://127.0.0.1:8080"))
    folder = hou.expandString("$HIP/volstyle")
    if kwargs and kwargs.get("shiftclick"):
        hou.session.volstyle = None
    state = getattr(hou.session, "volstyle", None)
    if state is not None:
        try:
            vs.get_session(state["sid"])
        except vc.NotFound:  # the server forgot it (restarted without its data folder): start over
            state = None
    if state is None:
        sop = hou.selectedNodes()[0] if hou.selectedNodes() else None
        path = sop.parm("file").eval() if sop is not None and sop.parm("file") is not None else None
        if not path:
            raise hou.Error("select a File SOP reading the VDB first (write a sim out with a ROP, then read it with a File SOP)")
        cams = {n.name(): houdini_camera(n) for n in hou.node("/obj").children() if n.type().name() == "cam"}
        lights = [houdini_sun(n) for n in hou.node("/obj").children() if n.type().name().startswith("hlight") and
                  n.parm("light_type") is not None and n.parm("light_type").evalAsString() == "distant"]
        sid = send(vs, path, lights)
        hou.session.volstyle = {"sid": sid, "views": render_views(vs, sid, cams, folder)}
        hou.ui.displayMessage(f"views rendered to {folder}: paint them as <camera>.painted.exr, then run the tool again")
        return
    send_paintings(vs, state["sid"], state["views"], folder)
    with hou.InterruptableOperation("volstyle solve", open_interrupt_dialog=True) as op:
        # Cancel raises hou.OperationInterrupted from the callback: Job.wait cancels the job.
        result = solve_and_fetch(vs, state["sid"], os.path.join(folder, "solved.vdb"), iterations=iterations,
                                 progress=lambda name, data: name == "progress" and op.updateProgress(
                                     data.get("iteration", 0) / float(iterations)))
    hou.session.volstyle = None  # the next click starts over with what the scene holds then
    hou.ui.displayMessage(f"solved: version {result['version']}; $HIP/volstyle/solved.vdb written")
