"""HTTP for the client on the standard library alone (urllib): the bearer token, JSON and binary
bodies, the SPEC's error body as exceptions, retries where a retry cannot do harm, and
text/event-stream reading."""
from __future__ import annotations

import http.client
import json
import socket
import time
import urllib.error
import urllib.parse
import urllib.request
from typing import Any, Iterator, Mapping

from .errors import ApiError, ConnectionFailed, Overloaded

USER_AGENT = "volstyle-client/1.0 (python)"


class Transport:
    """One server: `base_url` is where `/api/v1` lives (http://host:port)."""

    def __init__(self, base_url: str, token: str | None = None, timeout: float = 120.0, retries: int = 3, backoff: float = 0.5):
        base_url = base_url.strip().rstrip("/")
        if "://" not in base_url:  # "127.0.0.1:8080" means http
            base_url = "http://" + base_url
        if base_url.endswith("/api/v1"):  # the API's own address given: the server is above it
            base_url = base_url[: -len("/api/v1")]
        self.base_url = base_url
        self.api = self.base_url + "/api/v1"
        self.token = token
        self.timeout = timeout
        self.retries = retries
        self.backoff = backoff

    def headers(self) -> dict[str, str]:
        h = {"User-Agent": USER_AGENT}
        if self.token:
            h["Authorization"] = "Bearer " + self.token
        return h

    def url(self, path: str, query: Mapping[str, Any] | None = None) -> str:
        q = {k: _query_value(v) for k, v in (query or {}).items() if v is not None}
        return self.api + path + ("?" + urllib.parse.urlencode(q) if q else "")

    def request(self, method: str, path: str, *, json_body: Any = None, data: bytes | None = None,
                content_type: str | None = None, query: Mapping[str, Any] | None = None,
                headers: Mapping[str, str] | None = None, retry: bool | None = None) -> tuple[int, dict[str, str], bytes]:
        """Sends one request; returns (status, headers, body) for 2xx/304 and raises ApiError otherwise.

        Retries connection failures and 503 `overloaded` answers (after Retry-After) when `retry`
        is true; by default GET, PUT and DELETE retry (idempotent by HTTP), POST only with an
        Idempotency-Key header (the server answers a retry with the first request's result)."""
        h = self.headers()
        h.update(headers or {})
        body = data
        if json_body is not None:
            body = json.dumps(json_body).encode()
            content_type = "application/json"
        if body is not None:
            h["Content-Type"] = content_type or "application/octet-stream"
        elif method == "POST":
            h["Content-Length"] = "0"
        if retry is None:
            retry = method in ("GET", "PUT", "DELETE", "HEAD") or "Idempotency-Key" in h
        url = self.url(path, query)
        attempts = 1 + (self.retries if retry else 0)
        for attempt in range(attempts):
            req = urllib.request.Request(url, data=body, method=method, headers=h)
            try:
                with urllib.request.urlopen(req, timeout=self.timeout) as res:
                    return res.status, dict(res.headers.items()), res.read()
            except urllib.error.HTTPError as e:
                if e.code == 304:
                    return 304, dict(e.headers.items()), b""
                error = _api_error(e, method, url)
                if isinstance(error, Overloaded) and error.status == 503 and attempt + 1 < attempts:
                    time.sleep(min(30.0, error.retry_after or self.backoff * 2 ** attempt))
                    continue
                raise error from None
            except (urllib.error.URLError, ConnectionError, socket.timeout, TimeoutError) as e:
                if attempt + 1 < attempts:
                    time.sleep(self.backoff * 2 ** attempt)
                    continue
                raise ConnectionFailed(f"{method} {url}: {getattr(e, 'reason', e)}") from None
        raise AssertionError("unreachable")

    def json(self, method: str, path: str, **kw: Any) -> Any:
        _, _, body = self.request(method, path, **kw)
        return json.loads(body) if body else None

    def events(self, path: str, query: Mapping[str, Any] | None = None, timeout: float | None = None) -> Iterator[tuple[str, Any]]:
        """Yields (event, data) from a text/event-stream until the server closes it. `data` is
        parsed as JSON when it is JSON."""
        yield from self._stream(self.url(path, query), {"Accept": "text/event-stream"}, timeout, _parse_events)

    def parts(self, path: str, timeout: float | None = None) -> Iterator[tuple[dict[str, str], bytes]]:
        """Yields (headers, body) of each part of a multipart/x-mixed-replace stream (header names
        lower-case) until the server ends it."""
        yield from self._stream(self.url(path), {}, timeout, _parse_parts)

    def _stream(self, url: str, headers: Mapping[str, str], timeout: float | None, parse) -> Iterator[Any]:
        """GET `url` and yield what `parse` reads from the open response until the server ends it;
        errors as ApiError, a broken connection as ConnectionFailed."""
        req = urllib.request.Request(url, headers={**self.headers(), **headers})
        try:
            res = urllib.request.urlopen(req, timeout=timeout or self.timeout)
        except urllib.error.HTTPError as e:
            raise _api_error(e, "GET", req.full_url) from None
        except (urllib.error.URLError, ConnectionError, socket.timeout) as e:
            raise ConnectionFailed(f"GET {req.full_url}: {getattr(e, 'reason', e)}") from None
        with res:
            try:
                yield from parse(res)
            except (OSError, http.client.HTTPException) as e:  # a read timeout or reset mid-stream
                raise ConnectionFailed(f"GET {req.full_url}: the stream broke off ({e})") from None


def _parse_parts(res) -> Iterator[tuple[dict[str, str], bytes]]:
    """(headers, body) of each part of a multipart/x-mixed-replace stream, until its final boundary."""
    while True:
        line = res.readline()
        if not line:
            return
        line = line.strip()
        if not line.startswith(b"--"):
            continue  # the CRLF after a part's body
        if line.endswith(b"--"):
            return  # the final boundary
        headers: dict[str, str] = {}
        while True:
            h = res.readline().decode("latin-1").strip()
            if not h:
                break
            name, _, value = h.partition(":")
            headers[name.strip().lower()] = value.strip()
        yield headers, res.read(int(headers.get("content-length", "0")))


def _parse_events(res) -> Iterator[tuple[str, Any]]:
    """(event, data) of a text/event-stream: comment lines (keep-alives) are skipped."""
    event, data = "message", []
    for raw in res:
        line = raw.decode("utf-8").rstrip("\r\n")
        if not line:  # a blank line ends an event (text/event-stream)
            if data:
                text = "\n".join(data)
                try:
                    yield event, json.loads(text)
                except ValueError:
                    yield event, text
            event, data = "message", []
        elif line.startswith(":"):
            continue  # a comment: the server's keep-alive while a job is quiet
        else:
            name, _, value = line.partition(":")
            value = value[1:] if value.startswith(" ") else value
            if name == "event":
                event = value
            elif name == "data":
                data.append(value)


def _query_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v)


def _api_error(e: urllib.error.HTTPError, method: str, url: str) -> ApiError:
    raw = e.read()
    try:
        body = json.loads(raw)
    except ValueError:
        body = raw.decode("utf-8", "replace")
    retry_after = e.headers.get("Retry-After")
    return ApiError.from_body(e.code, body, method, url, float(retry_after) if retry_after and retry_after.isdigit() else None)
