"""The volstyle HTTP API (docs/API.md) as typed Python calls, one method per route.

Every method names its route with @route(operation_id, method, path), the operation of the
server's OpenAPI description (GET /api/v1/openapi.json); a test compares the two, so a route the
server gains without a method here fails CI. JSON answers come back as dicts and lists as the API
sends them, files as bytes (or written to `path=`), jobs as Job objects."""
from __future__ import annotations

import json
import os
import urllib.parse
import uuid
from typing import Any, Callable, Iterator, Mapping, Sequence, TypeVar

from .errors import LocalFileError
from .job import Job
from .transport import Transport

F = TypeVar("F", bound=Callable[..., Any])
Json = Any


def route(operation_id: str, method: str, path: str) -> Callable[[F], F]:
    """Marks a method as the client's call of one API operation."""

    def mark(fn: F) -> F:
        fn.route = (operation_id, method, path)  # type: ignore[attr-defined]
        return fn

    return mark


def _read(data: Any) -> bytes:
    """bytes as they are; a path (str or PathLike) read from disk."""
    if isinstance(data, (bytes, bytearray, memoryview)):
        return bytes(data)
    try:
        with open(os.fspath(data), "rb") as f:
            return f.read()
    except OSError as e:
        raise LocalFileError(f"cannot read '{os.fspath(data)}': {e.strerror}") from None


class Page(list):
    """One page of a listing: the items, and `next_cursor` (None on the last page) to pass as
    `cursor=` for the next."""

    next_cursor: str | None = None


def _seg(value: Any) -> str:
    """A path segment (ids, names) escaped."""
    return urllib.parse.quote(str(value), safe="")


def _fields(base: Mapping[str, Any] | None, **named: Any) -> dict:
    """A JSON body: `base` (a whole dict) and the named fields that are not None."""
    body = dict(base or {})
    body.update({k: v for k, v in named.items() if v is not None})
    return body


class Client:
    """A volstyle server. `Client("http://127.0.0.1:8080", token=…)`; the token defaults to
    $VOLSTYLE_TOKEN. Requests that cannot do harm twice (GET, PUT, DELETE, and POSTs that create
    sessions or jobs, which carry an Idempotency-Key) are retried on connection failures and 503."""

    def __init__(self, url: str = "http://127.0.0.1:8080", token: str | None = None, timeout: float = 120.0, retries: int = 3):
        self.http = Transport(url, token if token is not None else os.environ.get("VOLSTYLE_TOKEN"), timeout, retries)

    def __repr__(self) -> str:
        return f"Client({self.http.base_url!r})"

    @classmethod
    def routes(cls) -> dict[str, tuple[str, str, str]]:
        """{method name: (operation id, HTTP method, path)} for every route this client calls."""
        out = {}
        for name in dir(cls):
            r = getattr(getattr(cls, name), "route", None)
            if r:
                out[name] = r
        return out

    # ---- internals ------------------------------------------------------------------------------
    def _json(self, method: str, path: str, body: Any = None, **kw: Any) -> Json:
        return self.http.json(method, path, json_body=body, **kw)

    def _bytes(self, method: str, path: str, body: Any = None, path_out: Any = None, **kw: Any) -> bytes:
        if path_out is not None:  # a folder that is not there fails before the download, not after
            folder = os.path.dirname(os.path.abspath(os.fspath(path_out)))
            if not os.path.isdir(folder):
                raise LocalFileError(f"cannot write '{os.fspath(path_out)}': no folder '{folder}'")
        _, _, data = self.http.request(method, path, json_body=body, **kw)
        if path_out is not None:
            try:
                with open(os.fspath(path_out), "wb") as f:
                    f.write(data)
            except OSError as e:
                raise LocalFileError(f"cannot write '{os.fspath(path_out)}': {e.strerror}") from None
        return data

    def _upload(self, method: str, path: str, data: Any, **kw: Any) -> Json:
        return self.http.json(method, path, data=_read(data), content_type="application/octet-stream", **kw)

    def _job(self, path: str, body: dict, kind: str, idempotency_key: str | None, total: int | None = None) -> Job:
        key = idempotency_key or uuid.uuid4().hex  # a retry with the same key answers the same job
        answer = self.http.json("POST", path, json_body=body, headers={"Idempotency-Key": key})
        return Job(self, answer["job"], kind, total)

    def _page(self, path: str, query: dict) -> Page:
        _, headers, body = self.http.request("GET", path, query=query)
        page = Page(json.loads(body))
        page.next_cursor = next((v for k, v in headers.items() if k.lower() == "x-next-cursor"), None)
        return page

    def _pages(self, path: str, query: dict) -> Iterator[Json]:
        cursor = None
        while True:
            page = self._page(path, {**query, "cursor": cursor})
            yield from page
            cursor = page.next_cursor
            if not cursor:
                return

    # ---- the server ----------------------------------------------------------------------------
    @route("get_health", "GET", "/health")
    def health(self) -> Json:
        """The server's state: version, GL device, sessions, queue."""
        return self._json("GET", "/health")

    @route("get_schema_json", "GET", "/schema.json")
    def schema(self) -> Json:
        """The JSON Schema of every request and response body."""
        return self._json("GET", "/schema.json")

    @route("get_openapi_json", "GET", "/openapi.json")
    def openapi(self) -> Json:
        """The OpenAPI 3.1 description of every route."""
        return self._json("GET", "/openapi.json")

    @route("get_scenes", "GET", "/scenes")
    def scenes(self) -> Json:
        """The built-in scenes: [{name, description}]."""
        return self._json("GET", "/scenes")

    @route("get_quarantine", "GET", "/quarantine")
    def quarantine(self) -> Json:
        """Damaged files the server moved aside."""
        return self._json("GET", "/quarantine")

    # ---- sessions ------------------------------------------------------------------------------
    @route("post_sessions", "POST", "/sessions")
    def create_session(self, scene: str | None = None, resolution: int | None = None, *, body: dict | None = None,
                       idempotency_key: str | None = None) -> Json:
        """A new session from a built-in scene (`builtin:cloud`, …) at `resolution` voxels a side."""
        key = idempotency_key or uuid.uuid4().hex
        return self._json("POST", "/sessions", _fields(body, scene=scene, resolution=resolution), headers={"Idempotency-Key": key})

    @route("get_sessions", "GET", "/sessions")
    def list_sessions(self, limit: int | None = None, cursor: str | None = None) -> Page:
        """One page of sessions, oldest first; `.next_cursor` continues it (`iter_sessions`
        follows every page)."""
        return self._page("/sessions", {"limit": limit, "cursor": cursor})

    def iter_sessions(self, page_size: int = 100) -> Iterator[Json]:
        """Every session, page after page."""
        return self._pages("/sessions", {"limit": page_size})

    @route("get_sessions_sid", "GET", "/sessions/{sid}")
    def get_session(self, sid: str) -> Json:
        return self._json("GET", f"/sessions/{_seg(sid)}")

    @route("delete_sessions_sid", "DELETE", "/sessions/{sid}")
    def delete_session(self, sid: str) -> None:
        """Deletes the session (its jobs are cancelled)."""
        self.http.request("DELETE", f"/sessions/{_seg(sid)}")

    @route("post_sessions_sid_render", "POST", "/sessions/{sid}/render")
    def render(self, sid: str, camera: dict, format: str = "png", *, exposure: float | None = None, mode: str | None = None,
               translucent: dict | None = None, exr_type: str | None = None, path: Any = None) -> bytes:
        """Renders any camera: PNG (sRGB, `exposure` in stops) or EXR (layered, linear)."""
        body = _fields(None, camera=camera, format=format, exposure=exposure, mode=mode, translucent=translucent, exr_type=exr_type)
        return self._bytes("POST", f"/sessions/{_seg(sid)}/render", body, path)

    # ---- lighting ------------------------------------------------------------------------------
    @route("get_sessions_sid_lighting", "GET", "/sessions/{sid}/lighting")
    def get_lighting(self, sid: str) -> Json:
        return self._json("GET", f"/sessions/{_seg(sid)}/lighting")

    @route("put_sessions_sid_lighting", "PUT", "/sessions/{sid}/lighting")
    def set_lighting(self, sid: str, lighting: dict) -> Json:
        """Sets the lighting (docs/LIGHTING.md): sun/lights, background, phase, environment."""
        return self._json("PUT", f"/sessions/{_seg(sid)}/lighting", lighting)

    @route("get_sessions_sid_lighting_environment_format", "GET", "/sessions/{sid}/lighting/environment.{format}")
    def get_lighting_environment(self, sid: str, format: str = "exr", path: Any = None) -> bytes:
        """The environment light's lobes as a lat-long image (png or exr)."""
        return self._bytes("GET", f"/sessions/{_seg(sid)}/lighting/environment.{format}", path_out=path)

    @route("put_sessions_sid_environment", "PUT", "/sessions/{sid}/environment")
    def set_environment(self, sid: str, image: Any) -> Json:
        """Uploads the session's environment map (a lat-long EXR/HDR/PNG; bytes or a path)."""
        return self._upload("PUT", f"/sessions/{_seg(sid)}/environment", image)

    @route("delete_sessions_sid_environment", "DELETE", "/sessions/{sid}/environment")
    def delete_environment(self, sid: str) -> None:
        self.http.request("DELETE", f"/sessions/{_seg(sid)}/environment")

    @route("get_sessions_sid_environment_format", "GET", "/sessions/{sid}/environment.{format}")
    def get_environment(self, sid: str, format: str = "exr", path: Any = None) -> bytes:
        return self._bytes("GET", f"/sessions/{_seg(sid)}/environment.{format}", path_out=path)

    # ---- the volume and its versions -----------------------------------------------------------
    @route("put_sessions_sid_volume", "PUT", "/sessions/{sid}/volume")
    def upload_volume(self, sid: str, vdb: Any) -> Json:
        """Uploads a VDB (bytes or a path) as the session's new version; returns the session."""
        return self._upload("PUT", f"/sessions/{_seg(sid)}/volume", vdb)

    @route("get_sessions_sid_volume_vdb", "GET", "/sessions/{sid}/volume.vdb")
    def download_volume(self, sid: str, version: int | None = None, path: Any = None) -> bytes:
        """The current (or a given) version's VDB; written to `path` when given."""
        return self._bytes("GET", f"/sessions/{_seg(sid)}/volume.vdb", path_out=path, query={"version": version})

    @route("post_sessions_sid_perturb", "POST", "/sessions/{sid}/perturb")
    def perturb(self, sid: str, perturbation: dict) -> Json:
        """Bakes noise detail (docs/TRANSLUCENT.md) into a new version."""
        return self._json("POST", f"/sessions/{_seg(sid)}/perturb", perturbation)

    @route("post_sessions_sid_refraction", "POST", "/sessions/{sid}/refraction")
    def add_refraction(self, sid: str, refraction: dict) -> Json:
        """Gives the volume a generated refractive index (docs/REFRACTION.md), a new version."""
        return self._json("POST", f"/sessions/{_seg(sid)}/refraction", refraction)

    @route("delete_sessions_sid_refraction", "DELETE", "/sessions/{sid}/refraction")
    def remove_refraction(self, sid: str) -> Json:
        return self._json("DELETE", f"/sessions/{_seg(sid)}/refraction")

    @route("post_sessions_sid_revert", "POST", "/sessions/{sid}/revert")
    def revert(self, sid: str, version: int) -> Json:
        """A new version holding an older version's content."""
        return self._json("POST", f"/sessions/{_seg(sid)}/revert", {"version": version})

    @route("post_sessions_sid_undo", "POST", "/sessions/{sid}/undo")
    def undo(self, sid: str) -> Json:
        return self._json("POST", f"/sessions/{_seg(sid)}/undo")

    @route("post_sessions_sid_redo", "POST", "/sessions/{sid}/redo")
    def redo(self, sid: str) -> Json:
        return self._json("POST", f"/sessions/{_seg(sid)}/redo")

    # ---- animation frames (docs/ANIMATION.md) --------------------------------------------------
    @route("put_sessions_sid_frames_n", "PUT", "/sessions/{sid}/frames/{n}")
    def upload_frame(self, sid: str, n: int, vdb: Any) -> Json:
        return self._upload("PUT", f"/sessions/{_seg(sid)}/frames/{int(n)}", vdb)

    @route("delete_sessions_sid_frames_n", "DELETE", "/sessions/{sid}/frames/{n}")
    def delete_frame(self, sid: str, n: int) -> Json:
        return self._json("DELETE", f"/sessions/{_seg(sid)}/frames/{int(n)}")

    @route("put_sessions_sid_frames", "PUT", "/sessions/{sid}/frames")
    def upload_frames(self, sid: str, vdb: Any) -> Json:
        """One VDB holding every frame (grids named per frame, docs/ANIMATION.md)."""
        return self._upload("PUT", f"/sessions/{_seg(sid)}/frames", vdb)

    @route("get_sessions_sid_frames", "GET", "/sessions/{sid}/frames")
    def list_frames(self, sid: str) -> Json:
        return self._json("GET", f"/sessions/{_seg(sid)}/frames")

    @route("get_sessions_sid_frames_n_vdb", "GET", "/sessions/{sid}/frames/{n}.vdb")
    def download_frame(self, sid: str, n: int, path: Any = None) -> bytes:
        return self._bytes("GET", f"/sessions/{_seg(sid)}/frames/{int(n)}.vdb", path_out=path)

    @route("post_sessions_sid_animate", "POST", "/sessions/{sid}/animate")
    def animate(self, sid: str, options: dict | None = None, *, idempotency_key: str | None = None) -> Job:
        """Solves the key frames and fills the others (a job)."""
        return self._job(f"/sessions/{_seg(sid)}/animate", dict(options or {}), "animate", idempotency_key)

    @route("post_sessions_sid_frames_render", "POST", "/sessions/{sid}/frames/render")
    def render_frames(self, sid: str, options: dict, *, idempotency_key: str | None = None) -> Job:
        """Renders every frame with one camera (a job)."""
        return self._job(f"/sessions/{_seg(sid)}/frames/render", dict(options), "frames", idempotency_key)

    # ---- views, targets, weights, plates -------------------------------------------------------
    @route("post_sessions_sid_views", "POST", "/sessions/{sid}/views")
    def add_view(self, sid: str, camera: dict, frame: int | None = None) -> Json:
        """Adds a view (a camera; `frame` for an animation's key frame); returns it ({id, …})."""
        return self._json("POST", f"/sessions/{_seg(sid)}/views", _fields(None, camera=camera, frame=frame))

    @route("get_sessions_sid_views", "GET", "/sessions/{sid}/views")
    def list_views(self, sid: str) -> Json:
        return self._json("GET", f"/sessions/{_seg(sid)}/views")

    @route("get_sessions_sid_views_vid", "GET", "/sessions/{sid}/views/{vid}")
    def get_view(self, sid: str, vid: str) -> Json:
        return self._json("GET", f"/sessions/{_seg(sid)}/views/{_seg(vid)}")

    @route("delete_sessions_sid_views_vid", "DELETE", "/sessions/{sid}/views/{vid}")
    def delete_view(self, sid: str, vid: str) -> None:
        self.http.request("DELETE", f"/sessions/{_seg(sid)}/views/{_seg(vid)}")

    @route("put_sessions_sid_views_vid_target", "PUT", "/sessions/{sid}/views/{vid}/target")
    def set_target(self, sid: str, vid: str, image: Any, clip_aware: bool | None = None) -> Json:
        """Uploads the view's painted target (PNG/JPEG/TIFF/EXR/HDR, bytes or a path; alpha =
        weight). An 8/16-bit image's white pixels count as clipped (weight 0) unless
        `clip_aware=False`. `exr_rgba()` writes a linear float target with weights."""
        return self._upload("PUT", f"/sessions/{_seg(sid)}/views/{_seg(vid)}/target", image, query={"clip_aware": clip_aware})

    @route("delete_sessions_sid_views_vid_target", "DELETE", "/sessions/{sid}/views/{vid}/target")
    def delete_target(self, sid: str, vid: str) -> Json:
        return self._json("DELETE", f"/sessions/{_seg(sid)}/views/{_seg(vid)}/target")

    @route("put_sessions_sid_views_vid_weights", "PUT", "/sessions/{sid}/views/{vid}/weights")
    def set_weights(self, sid: str, vid: str, image: Any) -> Json:
        """A weight image (first channel) multiplying the target's alpha."""
        return self._upload("PUT", f"/sessions/{_seg(sid)}/views/{_seg(vid)}/weights", image)

    @route("delete_sessions_sid_views_vid_weights", "DELETE", "/sessions/{sid}/views/{vid}/weights")
    def delete_weights(self, sid: str, vid: str) -> Json:
        return self._json("DELETE", f"/sessions/{_seg(sid)}/views/{_seg(vid)}/weights")

    @route("put_sessions_sid_views_vid_background", "PUT", "/sessions/{sid}/views/{vid}/background")
    def set_background(self, sid: str, vid: str, image: Any) -> Json:
        """The view's plate: what lies behind the volume in its renders and solves."""
        return self._upload("PUT", f"/sessions/{_seg(sid)}/views/{_seg(vid)}/background", image)

    @route("delete_sessions_sid_views_vid_background", "DELETE", "/sessions/{sid}/views/{vid}/background")
    def delete_background(self, sid: str, vid: str) -> Json:
        return self._json("DELETE", f"/sessions/{_seg(sid)}/views/{_seg(vid)}/background")

    @route("get_sessions_sid_views_vid_background_format", "GET", "/sessions/{sid}/views/{vid}/background.{format}")
    def get_background(self, sid: str, vid: str, format: str = "exr", path: Any = None) -> bytes:
        return self._bytes("GET", f"/sessions/{_seg(sid)}/views/{_seg(vid)}/background.{format}", path_out=path)

    @route("get_sessions_sid_views_vid_target_png", "GET", "/sessions/{sid}/views/{vid}/target.png")
    def get_target(self, sid: str, vid: str, path: Any = None) -> bytes:
        """The view's target as PNG (alpha = weight)."""
        return self._bytes("GET", f"/sessions/{_seg(sid)}/views/{_seg(vid)}/target.png", path_out=path)

    @route("get_sessions_sid_views_vid_render_format", "GET", "/sessions/{sid}/views/{vid}/render.{format}")
    def render_view(self, sid: str, vid: str, format: str = "png", *, exposure: float | None = None, exr_type: str | None = None,
                    path: Any = None) -> bytes:
        """The view's camera rendered now: PNG (sRGB) or EXR (layered, linear; `exr_type="float"`)."""
        return self._bytes("GET", f"/sessions/{_seg(sid)}/views/{_seg(vid)}/render.{format}", path_out=path,
                           query={"exposure": exposure, "exr_type": exr_type})

    # ---- solving and jobs ----------------------------------------------------------------------
    @route("post_sessions_sid_solve", "POST", "/sessions/{sid}/solve")
    def solve(self, sid: str, options: dict | None = None, *, unknowns: Sequence[str] | None = None, max_iterations: int | None = None,
              idempotency_key: str | None = None, **more: Any) -> Job:
        """Starts a solve (options as in docs/API.md: unknowns, max_iterations, regularization, …)."""
        if isinstance(unknowns, str):  # "emission" or "emission,albedo"
            unknowns = [u.strip() for u in unknowns.split(",") if u.strip()]
        body = _fields(options, unknowns=list(unknowns) if unknowns else None, max_iterations=max_iterations, **more)
        return self._job(f"/sessions/{_seg(sid)}/solve", body, "solve", idempotency_key, body.get("max_iterations"))

    @route("get_jobs", "GET", "/jobs")
    def list_jobs(self, session: str | None = None, limit: int | None = None, cursor: str | None = None) -> Page:
        """One page of jobs (of a session), oldest first; `.next_cursor` continues it."""
        return self._page("/jobs", {"session": session, "limit": limit, "cursor": cursor})

    def iter_jobs(self, session: str | None = None, page_size: int = 100) -> Iterator[Json]:
        return self._pages("/jobs", {"session": session, "limit": page_size})

    def job(self, jid: str, kind: str = "job") -> Job:
        """A Job object for a known id (to wait on or cancel a job started elsewhere)."""
        return Job(self, jid, kind)

    @route("get_jobs_jid", "GET", "/jobs/{jid}")
    def get_job(self, jid: str) -> Json:
        return self._json("GET", f"/jobs/{_seg(jid)}")

    @route("delete_jobs_jid", "DELETE", "/jobs/{jid}")
    def cancel_job(self, jid: str) -> Json:
        return self._json("DELETE", f"/jobs/{_seg(jid)}")

    @route("get_jobs_jid_events", "GET", "/jobs/{jid}/events")
    def job_events(self, jid: str) -> Iterator[tuple[str, Any]]:
        """The job's events as (name, data) until its final event."""
        return self.http.events(f"/jobs/{_seg(jid)}/events")

    @route("get_jobs_jid_frames_i_png", "GET", "/jobs/{jid}/frames/{i}.png")
    def job_frame(self, jid: str, i: int, path: Any = None) -> bytes:
        return self._bytes("GET", f"/jobs/{_seg(jid)}/frames/{int(i)}.png", path_out=path)

    @route("get_jobs_jid_video_mp4", "GET", "/jobs/{jid}/video.mp4")
    def job_video(self, jid: str, path: Any = None) -> bytes:
        return self._bytes("GET", f"/jobs/{_seg(jid)}/video.mp4", path_out=path)

    @route("get_jobs_jid_preview_vid_png", "GET", "/jobs/{jid}/preview/{vid}.png")
    def job_preview(self, jid: str, vid: str, path: Any = None) -> bytes:
        """The job's latest iterate rendered from a view."""
        return self._bytes("GET", f"/jobs/{_seg(jid)}/preview/{_seg(vid)}.png", path_out=path)

    # ---- the light-shaft stylizer (docs/STYLIZER.md) -------------------------------------------
    @route("get_sessions_sid_stylizer", "GET", "/sessions/{sid}/stylizer")
    def get_stylizer(self, sid: str) -> Json:
        return self._json("GET", f"/sessions/{_seg(sid)}/stylizer")

    @route("put_sessions_sid_stylizer", "PUT", "/sessions/{sid}/stylizer")
    def set_stylizer(self, sid: str, scene: dict) -> Json:
        """Sets the stylizer's scene: occluders, light, medium, camera, transfer function."""
        return self._json("PUT", f"/sessions/{_seg(sid)}/stylizer", scene)

    @route("post_sessions_sid_stylizer_undo", "POST", "/sessions/{sid}/stylizer/undo")
    def stylizer_undo(self, sid: str) -> Json:
        return self._json("POST", f"/sessions/{_seg(sid)}/stylizer/undo")

    @route("post_sessions_sid_stylizer_redo", "POST", "/sessions/{sid}/stylizer/redo")
    def stylizer_redo(self, sid: str) -> Json:
        return self._json("POST", f"/sessions/{_seg(sid)}/stylizer/redo")

    @route("post_sessions_sid_stylizer_pick", "POST", "/sessions/{sid}/stylizer/pick")
    def stylizer_pick(self, sid: str, body: dict) -> Json:
        """What a pixel sees: V̄, depth, the occluder."""
        return self._json("POST", f"/sessions/{_seg(sid)}/stylizer/pick", body)

    @route("post_sessions_sid_stylizer_constraints", "POST", "/sessions/{sid}/stylizer/constraints")
    def stylizer_constraints(self, sid: str, body: dict) -> Json:
        """Pins the TF's colour where pixels' V̄ and depth are."""
        return self._json("POST", f"/sessions/{_seg(sid)}/stylizer/constraints", body)

    @route("post_sessions_sid_stylizer_sequence", "POST", "/sessions/{sid}/stylizer/sequence")
    def stylizer_sequence(self, sid: str, options: dict, *, idempotency_key: str | None = None) -> Job:
        """Renders a sequence (and a video) along the camera path (a job)."""
        return self._job(f"/sessions/{_seg(sid)}/stylizer/sequence", dict(options), "sequence", idempotency_key)

    @route("get_sessions_sid_stylizer_occluders", "GET", "/sessions/{sid}/stylizer/occluders")
    def list_occluders(self, sid: str) -> Json:
        return self._json("GET", f"/sessions/{_seg(sid)}/stylizer/occluders")

    @route("put_sessions_sid_stylizer_occluders_name", "PUT", "/sessions/{sid}/stylizer/occluders/{name}")
    def upload_occluder(self, sid: str, name: str, mesh: Any) -> Json:
        """Uploads an occluder mesh (OBJ, PLY, glTF/GLB; bytes or a path) under `name`."""
        return self._upload("PUT", f"/sessions/{_seg(sid)}/stylizer/occluders/{_seg(name)}", mesh)

    @route("delete_sessions_sid_stylizer_occluders_name", "DELETE", "/sessions/{sid}/stylizer/occluders/{name}")
    def delete_occluder(self, sid: str, name: str) -> None:
        self.http.request("DELETE", f"/sessions/{_seg(sid)}/stylizer/occluders/{_seg(name)}")

    @route("put_sessions_sid_stylizer_tf", "PUT", "/sessions/{sid}/stylizer/tf")
    def upload_stylizer_tf(self, sid: str, image: Any) -> Json:
        return self._upload("PUT", f"/sessions/{_seg(sid)}/stylizer/tf", image)

    @route("delete_sessions_sid_stylizer_tf", "DELETE", "/sessions/{sid}/stylizer/tf")
    def delete_stylizer_tf(self, sid: str) -> None:
        self.http.request("DELETE", f"/sessions/{_seg(sid)}/stylizer/tf")

    @route("get_sessions_sid_stylizer_tf_png", "GET", "/sessions/{sid}/stylizer/tf.png")
    def get_stylizer_tf(self, sid: str, path: Any = None) -> bytes:
        return self._bytes("GET", f"/sessions/{_seg(sid)}/stylizer/tf.png", path_out=path)

    @route("get_sessions_sid_stylizer_transfer_function_png", "GET", "/sessions/{sid}/stylizer/transfer_function.png")
    def get_stylizer_transfer_function(self, sid: str, path: Any = None) -> bytes:
        """The TF as the frame applies it (compiled layers)."""
        return self._bytes("GET", f"/sessions/{_seg(sid)}/stylizer/transfer_function.png", path_out=path)

    @route("post_sessions_sid_stylizer_frame", "POST", "/sessions/{sid}/stylizer/frame")
    def stylizer_frame(self, sid: str, options: dict | None = None, path: Any = None) -> bytes:
        """Renders a frame (or an AOV) of the stylizer's scene: PNG, JPEG or EXR bytes."""
        return self._bytes("POST", f"/sessions/{_seg(sid)}/stylizer/frame", dict(options or {}), path)

    @route("get_sessions_sid_stylizer_events", "GET", "/sessions/{sid}/stylizer/events")
    def stylizer_events(self, sid: str) -> Iterator[tuple[str, Any]]:
        """Live frames: a `frame` event per scene revision, until the session closes."""
        return self.http.events(f"/sessions/{_seg(sid)}/stylizer/events")

    @route("get_sessions_sid_stylizer_frames_rev_jpeg", "GET", "/sessions/{sid}/stylizer/frames/{rev}.jpeg")
    def stylizer_live_frame(self, sid: str, rev: int, path: Any = None) -> bytes:
        return self._bytes("GET", f"/sessions/{_seg(sid)}/stylizer/frames/{int(rev)}.jpeg", path_out=path)
