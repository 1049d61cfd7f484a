"""API calls: the server, sessions, lighting, the volume and its versions, animation frames."""
from __future__ import annotations

import uuid
from typing import Any, Iterator

from .client_base import ClientBase, Json, Page, _fields, _seg, route
from .job import Job


class SessionCalls(ClientBase):
    # ---- the server ----------------------------------------------------------------------------
    @route("get_health", "GET", "/health")
    def health(self) -> Json:
        """The server's state: version, GL device, sessions, queue."""
        return self._json("GET", "/health")

    @route("get_ready", "GET", "/ready")
    def ready(self) -> Json:
        """Readiness (a load balancer's check): {"status": "ready", "store", "gl_renderer"}; raises
        an ApiError (503 overloaded, saying why) when the store takes no writes, GL is down or the
        server is stopping."""
        return self._json("GET", "/ready")

    @route("get_metrics", "GET", "/metrics")
    def metrics(self) -> dict[str, float]:
        """The server's Prometheus metrics as {"name{labels}": value} (comments dropped)."""
        out: dict[str, float] = {}
        for line in self._bytes("GET", "/metrics").decode().splitlines():
            if line and not line.startswith("#"):
                key, _, value = line.rpartition(" ")
                out[key] = float(value)
        return out

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

    # ---- the viewport's live stream (issue #40) ------------------------------------------------
    @route("put_sessions_sid_viewport", "PUT", "/sessions/{sid}/viewport")
    def set_viewport(self, sid: str, camera: dict, *, exposure: float | None = None, mode: str | None = None,
                     translucent: dict | None = None) -> Json:
        """Sets what the viewport stream shows (render's options; frames are JPEG): {"revision", "shown"}."""
        body = _fields(None, camera=camera, exposure=exposure, mode=mode, translucent=translucent)
        return self._json("PUT", f"/sessions/{_seg(sid)}/viewport", body)

    @route("get_sessions_sid_viewport", "GET", "/sessions/{sid}/viewport")
    def get_viewport(self, sid: str) -> Json:
        """Where the viewport stands: {"revision": PUTs so far, "shown": edits of what renders show}."""
        return self._json("GET", f"/sessions/{_seg(sid)}/viewport")

    @route("get_sessions_sid_viewport_stream", "GET", "/sessions/{sid}/viewport/stream")
    def viewport_stream(self, sid: str) -> Iterator[tuple[dict[str, str], bytes]]:
        """The viewport's frames as they come: (part headers, body) per part — a JPEG per change of
        the viewport or of what the session shows (X-Revision, X-Shown, X-Version), JSON for a
        failed frame or the end. Close the iterator to close the stream."""
        return self.http.parts(f"/sessions/{_seg(sid)}/viewport/stream")

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
