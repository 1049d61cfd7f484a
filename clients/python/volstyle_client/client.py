"""The volstyle HTTP API (docs/API.md) as typed Python calls, one method per route.

Every method names its route with @route(operation_id, method, path), the operation of the
server's OpenAPI description (GET /api/v1/openapi.json); a test compares the two, so a route the
server gains without a method here fails CI. JSON answers come back as dicts and lists as the API
sends them, files as bytes (or written to `path=`), jobs as Job objects. The calls are grouped by
resource: session_calls.py, view_calls.py, stylizer_calls.py (on client_base.py)."""
from __future__ import annotations

from .client_base import Page, route
from .session_calls import SessionCalls
from .stylizer_calls import StylizerCalls
from .view_calls import ViewCalls

__all__ = ["Client", "Page", "route"]


class Client(SessionCalls, ViewCalls, StylizerCalls):
    """A volstyle server. `Client("http://127.0.0.1:8080", token=…)`; the token defaults to
    $VOLSTYLE_TOKEN. Requests that cannot do harm twice (GET, PUT, DELETE, and POSTs that create
    sessions or jobs, which carry an Idempotency-Key) are retried on connection failures and 503."""
