"""Who may ask the web app what: the token, the host names it answers to, the origin of writes.

Three ASGI middlewares wrap the app of :mod:`.app` (outermost first):

* :class:`HostCheck` — the ``Host`` header must name this server
  (:func:`~.hosts.allowed_hosts`: the address it listens on, ``localhost``/``127.0.0.1``/
  ``[::1]`` for a loopback address, and the ``--allowed-host`` names), with or without a port,
  else 403. A page whose domain an attacker rebinds to 127.0.0.1 (DNS rebinding) sends its own
  domain as ``Host`` and is refused, so it can neither read the API and the pictures nor write
  a scene.
* :class:`OriginCheck` — a request that changes state (any method but GET, HEAD and OPTIONS)
  whose ``Origin`` header is present must come from the page's own origin (the scheme's host
  and port are those of the ``Host`` header), else 403: another site's page in the user's
  browser cannot write a scene (cross-site request forgery).
* :class:`TokenCheck` — with a token, every request needs ``Authorization: Bearer TOKEN`` or
  ``?token=TOKEN``, else 401.

Starlette's ``TrustedHostMiddleware`` answers 400 in plain text, and the older Starlette
versions the ``serve`` extra allows (from 0.37) split the ``Host`` header at its first colon
(an IPv6 literal such as ``[::1]:8080`` never matches), hence a check of its own here, with 403
and the app's JSON error shape. The model is documented in ``docs/serve.md`` ("Security model").
"""

from __future__ import annotations

import hmac
from typing import Any, Callable
from urllib.parse import parse_qs, urlsplit

from starlette.responses import JSONResponse

from .hosts import HOST, host_name

__all__ = ["HostCheck", "OriginCheck", "TokenCheck"]

#: methods that only read: no origin check
_SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})
_DEFAULT_PORTS = {"http": 80, "https": 443}


def _header(scope: dict, name: bytes) -> str | None:
    for k, v in scope.get("headers", ()):
        if k == name:
            return v.decode("latin-1")
    return None


def _parse_host(value: str | None) -> tuple[str, int | None] | None:
    """A ``Host`` header as ``(name, port)`` (:func:`host_name`'s form; port None when the
    header has none), or None when it is missing or malformed."""
    m = HOST.fullmatch(value or "")
    if m is None:
        return None
    name = host_name(f"[{m['v6']}]" if m["v6"] is not None else m["name"])
    port = int(m["port"]) if m["port"] is not None else None
    return (name, port) if name is not None else None


def _refuse(status: int, message: str) -> JSONResponse:
    return JSONResponse({"error": message}, status_code=status)


class HostCheck:
    """ASGI middleware: the ``Host`` header must name one of ``hosts`` (any port), else 403.

    ``hosts``: names in :func:`host_name`'s form (:func:`~.hosts.allowed_hosts`)."""

    def __init__(self, app: Any, hosts: frozenset[str]) -> None:
        self.app, self.hosts = app, hosts
        shown = ", ".join(f"[{h}]" if ":" in h else h for h in sorted(hosts))
        self.message = (f"this server answers only to the host names {shown}; start it with "
                        f"--allowed-host NAME to add another")

    async def __call__(self, scope: dict, receive: Callable, send: Callable) -> None:
        if scope["type"] in ("http", "websocket"):
            host = _parse_host(_header(scope, b"host"))
            if host is None or host[0] not in self.hosts:
                await _refuse(403, self.message)(scope, receive, send)
                return
        await self.app(scope, receive, send)


def same_origin(origin: str, host: str | None) -> bool:
    """``origin`` (an ``Origin`` header) is the origin of a page served under the ``Host``
    header ``host``: the same host name and port (the scheme's default port when a header has
    none)."""
    try:
        parts = urlsplit(origin)
        scheme, name, port = parts.scheme.lower(), parts.hostname, parts.port
    except ValueError:
        return False
    parsed = _parse_host(host)
    if scheme not in _DEFAULT_PORTS or not name or parsed is None or parts.path \
            or parts.query or parts.username is not None:
        return False
    default = _DEFAULT_PORTS[scheme]
    return (host_name(name) == parsed[0]
            and (port or default) == (parsed[1] if parsed[1] is not None else default))


class OriginCheck:
    """ASGI middleware: a request other than GET, HEAD and OPTIONS with an ``Origin`` header
    that is not the page's own origin (:func:`same_origin`) is refused with 403. A request
    without ``Origin`` (``curl``, a script) passes: browsers send it with every such request,
    and it is what a cross-site page cannot forge."""

    def __init__(self, app: Any) -> None:
        self.app = app

    async def __call__(self, scope: dict, receive: Callable, send: Callable) -> None:
        if scope["type"] == "http" and scope.get("method", "GET") not in _SAFE_METHODS:
            origin = _header(scope, b"origin")
            if origin is not None and not same_origin(origin, _header(scope, b"host")):
                await _refuse(403, "a request that changes the server's state must come from "
                                   "its own page: the Origin header names another site"
                              )(scope, receive, send)
                return
        await self.app(scope, receive, send)


class TokenCheck:
    """ASGI middleware: every HTTP request needs ``Authorization: Bearer TOKEN`` or
    ``?token=TOKEN`` (an ``<img>`` or ``EventSource`` cannot set headers), else 401."""

    def __init__(self, app: Any, token: str) -> None:
        self.app, self.token = app, token.encode()

    def _allowed(self, scope: dict) -> bool:
        for k, v in scope.get("headers", ()):
            if k == b"authorization" and v[:7].lower() == b"bearer ":
                if hmac.compare_digest(v[7:].strip(), self.token):
                    return True
        qs = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        return any(hmac.compare_digest(t.encode("latin-1", "replace"), self.token)
                   for t in qs.get("token", []))

    async def __call__(self, scope: dict, receive: Callable, send: Callable) -> None:
        if scope["type"] == "http" and not self._allowed(scope):
            resp = JSONResponse({"error": "a token is required: Authorization: Bearer TOKEN or "
                                          "?token=TOKEN"}, status_code=401,
                                headers={"WWW-Authenticate": "Bearer"})
            await resp(scope, receive, send)
            return
        await self.app(scope, receive, send)
