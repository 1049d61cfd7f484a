"""API calls: the light-shaft stylizer (docs/STYLIZER.md)."""
from __future__ import annotations

from typing import Any, Iterator

from .client_base import ClientBase, Json, _seg, route
from .job import Job


class StylizerCalls(ClientBase):
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

    @route("get_sessions_sid_stylizer_stream", "GET", "/sessions/{sid}/stylizer/stream")
    def stylizer_stream(self, sid: str) -> Iterator[tuple[dict[str, str], bytes]]:
        """Live frames themselves (MJPEG): (headers, JPEG bytes) per scene revision, the headers
        naming it (`x-revision`, `x-width`, `x-height`, `x-render-ms`, `x-encode-ms`), until the
        session closes. A failed revision comes as an `application/json` part; stop iterating to
        close the stream."""
        return self.http.parts(f"/sessions/{_seg(sid)}/stylizer/stream")

    @route("get_sessions_sid_stylizer_frames_rev_jpeg", "GET", "/sessions/{sid}/stylizer/frames/{rev}.jpeg")
    def stylizer_live_frame(self, sid: str, rev: int, path: Any = None) -> bytes:
        return self._bytes("GET", f"/sessions/{_seg(sid)}/stylizer/frames/{int(rev)}.jpeg", path_out=path)
