"""What every group of API calls shares: the @route mark, the transport, JSON/bytes/upload/job/page
helpers (client.py composes the groups into Client)."""
from __future__ import annotations

import json
import os
import urllib.parse
import uuid
from typing import Any, Callable, Iterator, Mapping, TypeVar

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

class ClientBase:
    """The transport and the helpers the calls are written with."""

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
