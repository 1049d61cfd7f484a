"""Errors the client raises: each API error carries the SPEC's error body (docs/API.md)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass
class ErrorDetail:
    """One problem of a request: where (a JSON pointer, `?param` or header) and what."""

    path: str
    message: str


class VolstyleError(Exception):
    """Base of everything this package raises."""


class ConnectionFailed(VolstyleError):
    """The server could not be reached (after the retries an idempotent request allows)."""


class LocalFileError(VolstyleError):
    """A file on this machine could not be read or written (an upload's path, a download's)."""


@dataclass
class ApiError(VolstyleError):
    """An error answer: HTTP status and the body `{"error": {code, message, details, request_id}}`."""

    status: int
    code: str
    message: str
    details: list[ErrorDetail] = field(default_factory=list)
    request_id: str = ""
    method: str = ""
    url: str = ""
    retry_after: float | None = None

    def __post_init__(self) -> None:
        super().__init__(str(self))

    def __str__(self) -> str:
        where = f"{self.method} {self.url}: " if self.method else ""
        text = f"{where}{self.status} {self.code}: {self.message}"
        extra = [f"{d.path}: {d.message}" for d in self.details if f"{d.path}: {d.message}" not in self.message]
        if extra:  # what the message does not already say
            text += " — " + "; ".join(extra)
        return text

    @classmethod
    def from_body(cls, status: int, body: Any, method: str = "", url: str = "", retry_after: float | None = None) -> "ApiError":
        error = body.get("error") if isinstance(body, dict) else None
        if not isinstance(error, dict):  # not the SPEC's body (a proxy's page): keep what is known
            return _by_status(status)(status, "http_" + str(status), str(body)[:200], [], "", method, url, retry_after)
        details = [ErrorDetail(str(d.get("path", "")), str(d.get("message", ""))) for d in error.get("details", [])]
        kind = _BY_CODE.get(str(error.get("code")), _by_status(status))
        return kind(status, str(error.get("code")), str(error.get("message")), details, str(error.get("request_id", "")), method, url,
                    retry_after)


class InvalidRequest(ApiError):
    """400/415/422: the request is wrong (`details` name each field)."""


class Unauthorized(ApiError):
    """401: the bearer token is missing or wrong."""


class NotFound(ApiError):
    """404: no such route, session, view, job or version (the message names it)."""


class Conflict(ApiError):
    """409: the resource is busy, or nothing to undo/redo, or a retry of a request still running."""


class TooLarge(ApiError):
    """413: a body, upload or volume over the server's limit (the message names it)."""


class Overloaded(ApiError):
    """429/503: the server or the session is at a limit; `retry_after` says when to try again."""


class ServerError(ApiError):
    """5xx: the server failed (GPU, I/O, a bug)."""


class JobFailed(VolstyleError):
    """A job ended failed (or cancelled: JobCancelled); `job` is its final JSON; `code`,
    `message` and `details` are its SPEC error."""

    def __init__(self, job: dict):
        self.job = job
        err = job.get("error") or {}
        self.state = job.get("state", "failed")
        self.code = err.get("code", self.state)
        self.message = err.get("message", self.state)
        self.details = [ErrorDetail(str(d.get("path", "")), str(d.get("message", ""))) for d in err.get("details", [])]
        super().__init__(f"job {job.get('id')} {self.state}: {self.message}" + ("" if self.code == self.state else f" ({self.code})"))

    @staticmethod
    def of(job: dict) -> "JobFailed":
        return JobCancelled(job) if job.get("state") == "cancelled" else JobFailed(job)


class JobCancelled(JobFailed):
    """A job ended cancelled (by DELETE /jobs/{jid}, or by its session's deletion)."""


_BY_CODE = {
    "invalid_argument": InvalidRequest, "unknown_field": InvalidRequest, "invalid_json": InvalidRequest,
    "unsupported_media": InvalidRequest, "idempotency_conflict": InvalidRequest, "over_budget": InvalidRequest,
    "unauthorized": Unauthorized, "not_found": NotFound, "method_not_allowed": InvalidRequest, "busy": Conflict,
    "too_large": TooLarge, "too_many_jobs": Overloaded, "too_many_sessions": Overloaded, "too_many_streams": Overloaded,
    "too_many_connections": Overloaded, "overloaded": Overloaded, "out_of_budget": TooLarge,
}


def _by_status(status: int) -> type:
    if status == 401:
        return Unauthorized
    if status == 404:
        return NotFound
    if status == 409:
        return Conflict
    if status == 413:
        return TooLarge
    if status in (429, 503):
        return Overloaded
    if status >= 500:
        return ServerError
    return InvalidRequest
