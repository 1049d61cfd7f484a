"""API calls: views (targets, weights, plates), solving and jobs."""
from __future__ import annotations

from typing import Any, Iterator, Sequence

from .client_base import ClientBase, Json, Page, _fields, _seg, route
from .job import Job


class ViewCalls(ClientBase):
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
