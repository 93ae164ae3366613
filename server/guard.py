"""The request guard: what every HTTP request and WebSocket upgrade passes before it reaches a route.

In this order, each refusal a `{"detail": ...}` a person can act on:

1. **Host** (400): the app answers only its own names (`Settings.allowed_hosts`, loopback by
   default, plus the address it is bound to), so a page of another site whose name was made to
   resolve to this machine (DNS rebinding) gets nothing.
2. **Token** (401): with `Settings.token` set (required on a non-loopback address, see
   `mtrnn serve`), every request carries it, as ``Authorization: Bearer <token>`` or the cookie the
   app set. A page load ``GET /?token=<token>`` is answered with that cookie (HttpOnly,
   SameSite=Strict) and a redirect to the same URL without the token: the browser's later
   requests (fetch, EventSource, WebSocket, the 3D view's iframe) carry the cookie by themselves.
3. **Origin** (403): a state-changing request (POST, PUT, PATCH, DELETE) or a WebSocket upgrade
   whose ``Origin`` (or, without one, ``Referer``) is not this app's own origin is refused, so a
   form on another site cannot start a job or describe an upload. A request with neither header
   (curl, scripts) is not a browser's cross-site request and passes.
4. **JSON body size** (413): a request body that is not a multipart upload is read up to
   `Settings.max_json_bytes` before the route parses it (chunked bodies too); one byte more and
   it is refused without being parsed.
"""

from __future__ import annotations

import contextlib
import hmac
import ipaddress
import json
import socket
from collections.abc import Awaitable, Callable, MutableMapping
from typing import Any
from urllib.parse import parse_qsl, urlencode, urlsplit

from server.settings import Settings

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]

STATE_CHANGING = frozenset({"POST", "PUT", "PATCH", "DELETE"})
WILDCARD_HOSTS = frozenset({"0.0.0.0", "::", ""})
TOKEN_PARAM = "token"


def is_loopback(host: str) -> bool:
    """Whether `host` (a name or an address) is this machine only."""
    name = host.strip("[]").lower()
    if name == "localhost":
        return True
    try:
        return ipaddress.ip_address(name).is_loopback
    except ValueError:
        return False


def _this_machine() -> set[str]:
    """The names and addresses of this machine (for an app bound to every interface)."""
    names = {socket.gethostname(), socket.getfqdn()}
    with contextlib.suppress(OSError):
        names |= {str(info[4][0]) for info in socket.getaddrinfo(socket.gethostname(), None)}
    return names


def allowed_hosts(settings: Settings) -> frozenset[str]:
    """The Host names the app answers: the configured ones, plus the bound address (or, bound to
    every interface, this machine's names and addresses)."""
    names = set(settings.allowed_hosts)
    names |= _this_machine() if settings.host in WILDCARD_HOSTS else {settings.host}
    return frozenset(n.strip("[]").lower() for n in names if n)


def host_name(netloc: str) -> str:
    """``example.org:8000`` -> ``example.org``; ``[::1]:8000`` -> ``::1`` (lower case)."""
    netloc = netloc.strip().lower()
    if netloc.startswith("["):
        return netloc[1 : netloc.find("]")] if "]" in netloc else netloc
    return netloc.rsplit(":", 1)[0] if netloc.count(":") == 1 else netloc


def cookie_name(settings: Settings) -> str:
    """The token's cookie; named by port, since cookies are shared by every port of a host."""
    return f"mtrnn-token-{settings.port}"


def _headers(scope: Scope) -> dict[str, str]:
    return {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])}


def _cookies(header: str) -> dict[str, str]:
    pairs = (part.strip().split("=", 1) for part in header.split(";") if "=" in part)
    return {k.strip(): v.strip() for k, v in pairs}


def _same(a: str, b: str) -> bool:
    return hmac.compare_digest(a.encode(), b.encode())


class RequestGuard:
    """ASGI middleware applying the four checks above to `app`."""

    def __init__(self, app: ASGIApp, settings: Settings) -> None:
        self.app = app
        self.settings = settings
        self.hosts = allowed_hosts(settings)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = _headers(scope)
        refusal = self._refusal(scope, headers)
        if refusal is not None:
            await _refuse(scope, receive, send, *refusal)
            return
        if scope["type"] == "http" and self.settings.token and self._token_in_query(scope):
            await _set_cookie_and_redirect(scope, send, cookie_name(self.settings), self.settings.token)
            return
        if scope["type"] == "http" and _has_json_body(scope, headers):
            await self._bounded(scope, receive, send, headers)
            return
        await self.app(scope, receive, send)

    def _refusal(self, scope: Scope, headers: dict[str, str]) -> tuple[int, str] | None:
        host = headers.get("host", "")
        if host_name(host) not in self.hosts:
            return 400, (
                f"this app does not answer the host name {host_name(host) or '(none)'!r}; "
                "open it by one of its own names, or add the name to MTRNN_ALLOWED_HOSTS"
            )
        if self.settings.token and not self._authorised(scope, headers):
            return 401, (
                "this app needs its access token: open the URL `mtrnn serve` printed (it ends in "
                "?token=...), or send the header 'Authorization: Bearer <token>'"
            )
        if (scope["type"] == "websocket" or scope["method"] in STATE_CHANGING) and not _own_origin(
            headers, host
        ):
            return 403, "refused: this request comes from a page of another origin"
        return None

    def _authorised(self, scope: Scope, headers: dict[str, str]) -> bool:
        token = self.settings.token or ""
        auth = headers.get("authorization", "")
        if auth[:7].lower() == "bearer " and _same(auth[7:].strip(), token):
            return True
        cookie = _cookies(headers.get("cookie", "")).get(cookie_name(self.settings))
        if cookie is not None and _same(cookie, token):
            return True
        return self._token_in_query(scope) and scope["type"] == "http" and scope["method"] in ("GET", "HEAD")

    def _token_in_query(self, scope: Scope) -> bool:
        query = dict(parse_qsl(scope.get("query_string", b"").decode("latin-1")))
        return TOKEN_PARAM in query and _same(query[TOKEN_PARAM], self.settings.token or "")

    async def _bounded(self, scope: Scope, receive: Receive, send: Send, headers: dict[str, str]) -> None:
        limit = self.settings.max_json_bytes
        declared = headers.get("content-length", "")
        if declared.isdigit() and int(declared) > limit:
            await _refuse(scope, receive, send, 413, _too_large(limit))
            return
        chunks, size, more = [], 0, True
        while more:
            message = await receive()
            if message["type"] == "http.disconnect":
                return
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > limit:
                await _refuse(scope, receive, send, 413, _too_large(limit))
                return
            chunks.append(chunk)
            more = message.get("more_body", False)
        body = b"".join(chunks)
        replayed = False

        async def replay() -> Message:
            nonlocal replayed
            if replayed:
                return await receive()
            replayed = True
            return {"type": "http.request", "body": body, "more_body": False}

        await self.app(scope, replay, send)


def _too_large(limit: int) -> str:
    return f"the request body is larger than {limit:,} bytes, the most a JSON request may carry"


def _has_json_body(scope: Scope, headers: dict[str, str]) -> bool:
    """Every body but a multipart upload is parsed as JSON by the routes (FastAPI reads a body
    without a Content-Type as JSON too)."""
    if scope["method"] in ("GET", "HEAD", "OPTIONS"):
        return False
    return not headers.get("content-type", "").lower().startswith("multipart/")


def _own_origin(headers: dict[str, str], host: str) -> bool:
    origin = headers.get("origin") or headers.get("referer")
    if origin is None:
        return True  # not a browser's cross-site request (curl, scripts, the test client)
    parts = urlsplit(origin)
    return parts.scheme in ("http", "https") and parts.netloc.lower() == host.strip().lower()


async def _refuse(scope: Scope, receive: Receive, send: Send, status: int, detail: str) -> None:
    if scope["type"] == "websocket":
        await receive()  # websocket.connect
        await send({"type": "websocket.close", "code": 1008, "reason": detail[:120]})
        return
    body = json.dumps({"detail": detail}).encode()
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())],
        }
    )
    await send({"type": "http.response.body", "body": body})


async def _set_cookie_and_redirect(scope: Scope, send: Send, name: str, token: str) -> None:
    """Answer ``GET /path?token=...`` with the token's cookie and a redirect to ``/path``."""
    pairs = parse_qsl(scope.get("query_string", b"").decode("latin-1"))
    query = [(k, v) for k, v in pairs if k != TOKEN_PARAM]
    location = scope.get("root_path", "") + scope["path"] + (f"?{urlencode(query)}" if query else "")
    cookie = f"{name}={token}; HttpOnly; SameSite=Strict; Path=/"
    await send(
        {
            "type": "http.response.start",
            "status": 303,
            "headers": [
                (b"location", location.encode("latin-1")),
                (b"set-cookie", cookie.encode("latin-1")),
                (b"cache-control", b"no-store"),
                (b"content-length", b"0"),
            ],
        }
    )
    await send({"type": "http.response.body", "body": b""})
