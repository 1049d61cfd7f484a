"""volstyle's Python client: the HTTP API (docs/API.md) as typed calls, jobs that stream their
progress, errors that carry the server's error body, and the camera and image helpers a
pipeline needs (docs/CLIENTS.md).

    from volstyle_client import Client
    vs = Client("http://127.0.0.1:8080")
    s = vs.create_session("builtin:cloud", 64)
    v = vs.add_view(s["id"], {"eye": [0, 0.2, 3.4], "target": [0, 0, 0], "width": 256, "height": 256})
    vs.set_target(s["id"], v["id"], "painted.exr")
    result = vs.solve(s["id"], unknowns=["emission", "albedo"]).wait()
    vs.download_volume(s["id"], path="solved.vdb")
"""
from .camera import BLENDER_FROM_VOLSTYLE, camera_from_dcc, camera_from_houdini, field_of_view_y, invert, project, sun_from_dcc
from .client import Client, Page, route
from .errors import (ApiError, Conflict, ConnectionFailed, ErrorDetail, InvalidRequest, JobCancelled, JobFailed, LocalFileError, NotFound,
                     Overloaded, ServerError, TooLarge, Unauthorized, VolstyleError)
from .images import exr_rgba, picture_of, read_exr, write_exr
from .job import Job

__version__ = "1.0.0"
__all__ = [
    "Client", "Job", "Page", "route", "ApiError", "Conflict", "ConnectionFailed", "ErrorDetail", "InvalidRequest", "JobCancelled",
    "JobFailed", "LocalFileError", "NotFound", "Overloaded", "ServerError", "TooLarge", "Unauthorized", "VolstyleError",
    "BLENDER_FROM_VOLSTYLE", "camera_from_dcc", "camera_from_houdini",
    "field_of_view_y", "invert", "project", "sun_from_dcc", "exr_rgba", "picture_of", "read_exr", "write_exr",
]
