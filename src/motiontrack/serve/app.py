"""The web app of ``motiontrack serve``: the page, the JSON API, the MJPEG and event streams.

Starlette (an ASGI toolkit: routing, requests, streaming responses) served by uvicorn; a
handful of routes needs nothing more. No path taken from a request reaches the file system:
cameras are looked up by name in the hub, scene files are the ones the cameras file names, the
page's assets and the files' JSON Schemas are fixed lists. Routes are documented in
``docs/serve.md``.
"""

from __future__ import annotations

import asyncio
import hashlib
import json
from importlib import resources
from pathlib import Path
from typing import Any, AsyncIterator, Callable, Mapping

import anyio
from starlette.applications import Starlette
from starlette.requests import ClientDisconnect, Request
from starlette.responses import JSONResponse, Response, StreamingResponse
from starlette.routing import Route

from ..analytics.scene import scene_json_schema
from ..errors import ConfigError, MotionTrackError
from .cameras import cameras_json_schema
from .guard import HostCheck, OriginCheck, TokenCheck
from .hosts import LOOPBACK_NAMES
from .hub import CameraState, Cursor, Hub
from .scenes import SceneFiles
from .metrics import metrics_routes
from .mjpeg import MJPEG_TYPE, WALL_HEADER, part
from .search import search_routes

__all__ = ["create_app", "json_body", "MAX_BODY", "MAX_DEPTH"]

#: largest request body accepted (a scene of hundreds of lines and zones fits)
MAX_BODY = 64 * 1024
#: deepest nesting of a request's JSON (the editor's scene is 5 levels deep: object, lines,
#: line, points, point)
MAX_DEPTH = 16
#: largest integer a request's JSON may hold: TOML's integers are 64-bit
_MAX_INT = 2**63 - 1
_ASSETS = {"index.html": "text/html; charset=utf-8", "app.js": "text/javascript; charset=utf-8",
           "style.css": "text/css; charset=utf-8", "review.html": "text/html; charset=utf-8",
           "review.js": "text/javascript; charset=utf-8"}
#: seconds between keep-alive comments on an idle event stream
_KEEPALIVE_S = 15.0


def _error(status: int, message: str) -> JSONResponse:
    return JSONResponse({"error": message}, status_code=status)


async def _body(request: Request) -> bytes | Response:
    """The request body, or a 413 response when it is larger than :data:`MAX_BODY` (said by
    its ``Content-Length`` before any of it is read, or found while reading it), or a 400
    response, which nobody receives, when the client left before sending all of it."""
    length = request.headers.get("content-length")
    if length is not None and (not length.isdigit() or int(length) > MAX_BODY):
        return _error(413, f"request body larger than {MAX_BODY} bytes")
    data = bytearray()
    try:
        async for chunk in request.stream():
            data += chunk
            if len(data) > MAX_BODY:
                return _error(413, f"request body larger than {MAX_BODY} bytes")
    except ClientDisconnect:
        return _error(400, "the client left before sending the whole body")
    return bytes(data)


def json_body(body: bytes) -> Any:
    """``body`` parsed as JSON, no deeper than :data:`MAX_DEPTH` and with integers TOML can
    hold.

    Raises
    ------
    ConfigError
        The body is not JSON, is nested deeper, or holds a longer integer; one line.
    """
    try:
        data = json.loads(body)
    except RecursionError:   # Python's parser recurses per level: thousands of '[' end it
        raise ConfigError(f"the body is nested deeper than {MAX_DEPTH} levels") from None
    except json.JSONDecodeError as exc:
        raise ConfigError(f"the body must be a JSON object: {exc.msg} at line {exc.lineno} "
                          f"column {exc.colno}") from None
    except ValueError:       # an integer over Python's 4300 digits, or bytes not UTF-8
        raise ConfigError("the body must be a JSON object in UTF-8 with numbers of at most "
                          "19 digits") from None
    stack = [(data, 1)]
    while stack:
        value, depth = stack.pop()
        if isinstance(value, (dict, list)):
            if depth > MAX_DEPTH:
                raise ConfigError(f"the body is nested deeper than {MAX_DEPTH} levels")
            stack += [(v, depth + 1) for v in (value.values() if isinstance(value, dict)
                                                else value)]
        elif isinstance(value, int) and not isinstance(value, bool) and abs(value) > _MAX_INT:
            raise ConfigError(f"the body holds an integer of {len(str(abs(value)))} digits; "
                              f"integers must be within +-{_MAX_INT} (64 bits, as in TOML)")
    return data


def create_app(hub: Hub, token: str | None = None,
               scenes: Mapping[str, Path | None] | SceneFiles | None = None,
               stopping: Callable[[], bool] = lambda: False,
               hosts: frozenset[str] | None = LOOPBACK_NAMES,
               store: Path | None = None, review_only: bool = False) -> Any:
    """The ASGI app over ``hub``. ``scenes``: each camera's scene file (None: the camera has
    none; the editor's PUT then answers 409). ``stopping`` tells the streams to end (the server
    is shutting down). ``hosts``: the host names the app answers to
    (:func:`~.guard.allowed_hosts`; None: any), ``token``: the token every request needs
    (:mod:`.guard`); ``store``: the event store the search answers from (:mod:`.search`);
    ``review_only``: no cameras, ``/`` is the review page (``serve --review``)."""
    files = scenes if isinstance(scenes, SceneFiles) else SceneFiles(scenes or {})
    routes = [*_page_routes(review_only), *_api_routes(hub), *_stream_routes(hub, stopping),
              *_editor_routes(hub, files), *_schema_routes(), *search_routes(store),
              *metrics_routes(hub)]
    app: Any = OriginCheck(Starlette(routes=routes))
    if token:
        app = TokenCheck(app, token)
    return HostCheck(app, hosts) if hosts is not None else app


def _camera(hub: Hub, request: Request) -> CameraState | Response:
    """The camera the path names, or a 404 response."""
    cam = hub.get(request.path_params["name"])
    return cam if cam is not None else _error(404, "no such camera")


def _page_routes(review_only: bool = False) -> list[Route]:
    """The live page (``/``), the review page (``/review``; also ``/`` with ``review_only``)
    and their fixed list of assets."""

    async def page(request: Request) -> Response:
        return _asset("review.html" if review_only else "index.html")

    async def review(request: Request) -> Response:
        return _asset("review.html")

    async def asset(request: Request) -> Response:
        name = request.path_params["file"]
        return _asset(name) if name in _ASSETS else _error(404, "not found")

    return [Route("/", page), Route("/review", review), Route("/static/{file}", asset)]


def _api_routes(hub: Hub) -> list[Route]:
    """The JSON API: the cameras, each camera's events since a sequence number, its counts and
    its latest picture."""

    async def cameras(request: Request) -> Response:
        return JSONResponse([c.describe() for c in hub.cameras.values()])

    async def events(request: Request) -> Response:
        cam = _camera(hub, request)
        if isinstance(cam, Response):
            return cam
        raw = request.query_params.get("since", "0")
        try:
            since = int(raw)
        except ValueError:
            return _error(400, "since must be an integer sequence number")
        return JSONResponse(cam.events_since(since))

    async def counts(request: Request) -> Response:
        cam = _camera(hub, request)
        if isinstance(cam, Response):
            return cam
        with cam.lock:
            return JSONResponse(cam.counts)

    async def snapshot(request: Request) -> Response:
        cam = _camera(hub, request)
        if isinstance(cam, Response):
            return cam
        with cam.lock:
            jpeg, wall = cam.jpeg, cam.wall
        if jpeg is None:
            return _error(404, "no picture yet")
        headers = {"Cache-Control": "no-store"}
        if wall is not None:
            headers[WALL_HEADER] = f"{wall:.4f}"
        return Response(jpeg, media_type="image/jpeg", headers=headers)

    return [
        Route("/api/cameras", cameras),
        Route("/api/cameras/{name}/events", events),
        Route("/api/cameras/{name}/counts", counts),
        Route("/api/cameras/{name}/snapshot.jpg", snapshot),
    ]


def _stream_routes(hub: Hub, stopping: Callable[[], bool]) -> list[Route]:
    """The streams: each camera's MJPEG pictures and every camera's events (server-sent)."""

    async def stream(request: Request) -> Response:
        cam = _camera(hub, request)
        if isinstance(cam, Response):
            return cam
        return StreamingResponse(_mjpeg_parts(hub, cam, stopping),
                                 headers={"Cache-Control": "no-store"},
                                 media_type=MJPEG_TYPE)

    async def event_stream(request: Request) -> Response:
        # a reconnecting EventSource sends the id of the last message it received: the events
        # it missed meanwhile come first (Cursor)
        after = Cursor.parse(request.headers.get("last-event-id"))
        return StreamingResponse(_event_lines(hub, after, stopping),
                                 media_type="text/event-stream",
                                 headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"})

    return [Route("/api/cameras/{name}/stream.mjpg", stream), Route("/api/events", event_stream)]


async def _mjpeg_parts(hub: Hub, cam: CameraState,
                       stopping: Callable[[], bool]) -> AsyncIterator[bytes]:
    """The MJPEG parts of ``cam``: its latest picture, then every new one until ``stopping``."""
    sub = hub.subscribe_frames(cam)
    try:
        with cam.lock:
            latest = (cam.jpeg, cam.wall)
        if latest[0] is not None:
            yield part(*latest)
        while not stopping():
            try:
                jpeg, wall = await asyncio.wait_for(sub.queue.get(), 1.0)
            except asyncio.TimeoutError:
                continue
            yield part(jpeg, wall)
    finally:
        hub.unsubscribe_frames(cam, sub)


async def _event_lines(hub: Hub, after: Cursor | None,
                       stopping: Callable[[], bool]) -> AsyncIterator[bytes]:
    """The server-sent messages of every camera's events after ``after``, each with the cursor
    that resumes after it as its id, and a keep-alive comment when idle."""
    sub, cursor, missed = hub.subscribe_events(after=after)
    idle = 0.0

    def message(item: dict) -> bytes:
        cursor.seqs[item["camera"]] = item["seq"]
        return f"id: {cursor}\ndata: {json.dumps(item)}\n\n".encode()

    try:
        # the id alone: where this stream starts, for a reconnection before any event
        yield f": connected\nid: {cursor}\n\n".encode()
        for item in missed:
            yield message(item)
        while not stopping():
            try:
                item = await asyncio.wait_for(sub.queue.get(), 1.0)
            except asyncio.TimeoutError:
                idle += 1.0
                if idle >= _KEEPALIVE_S:
                    idle = 0.0
                    yield b": keep-alive\n\n"
                continue
            idle = 0.0
            yield message(item)
    finally:
        hub.unsubscribe_events(sub)


def _editor_routes(hub: Hub, files: SceneFiles) -> list[Route]:
    """The scene editor: a camera's scene file read (with the picture size) and written.

    Reading, parsing and checking a scene run in worker threads: a large scene takes long to
    check, and the event loop meanwhile keeps serving every other request and stream. Writes
    are checked one at a time (a scene file is written by one request at a time anyway), so
    that many of them occupy one thread, not the pool."""
    writers: list[anyio.CapacityLimiter] = []   # made on the event loop, by the first write

    async def get_scene(request: Request) -> Response:
        cam = _camera(hub, request)
        if isinstance(cam, Response):
            return cam
        try:
            data = await anyio.to_thread.run_sync(files.read, cam.name)
        except MotionTrackError as exc:   # no scene file, or one that cannot be read: a state
            return _error(409, str(exc))   # of the files, not a fault of the server
        with cam.lock:
            data["width"] = cam.status.get("width")
            data["height"] = cam.status.get("height")
        return JSONResponse(data)

    def write(name: str, body: bytes, size: tuple[int, int] | None) -> dict:
        return files.write(name, json_body(body), size)

    async def put_scene(request: Request) -> Response:
        cam = _camera(hub, request)
        if isinstance(cam, Response):
            return cam
        body = await _body(request)
        if isinstance(body, Response):
            return body
        if files.path(cam.name) is None:
            return _error(409, f"camera {cam.name} has no scene file in the cameras file")
        with cam.lock:
            w, h = cam.status.get("width"), cam.status.get("height")
        if not writers:
            writers.append(anyio.CapacityLimiter(1))
        try:
            saved = await anyio.to_thread.run_sync(write, cam.name, body,
                                                   (w, h) if w and h else None,
                                                   limiter=writers[0])
        except MotionTrackError as exc:
            return _error(400, str(exc))
        return JSONResponse(saved)

    return [Route("/api/cameras/{name}/scene", get_scene, methods=["GET"]),
            Route("/api/cameras/{name}/scene", put_scene, methods=["PUT"])]


def _schema_routes() -> list[Route]:
    """The JSON Schemas (draft 2020-12) of the scene file and the cameras file, which the
    editor checks a scene against before it sends it. Each is built once: the rules that make
    up the scene file's schema are registered when the app is created, and an ETag lets a page
    that opens again revalidate instead of downloading it."""
    bodies = {"scene": _Cached.of(scene_json_schema()),
              "cameras": _Cached.of(cameras_json_schema())}

    async def schema(request: Request) -> Response:
        cached = bodies.get(request.path_params["file"])
        return cached.response(request) if cached else _error(404, "no such schema")

    return [Route("/api/schema/{file}", schema)]


class _Cached:
    """A JSON body served with an ETag: a request whose ``If-None-Match`` names it gets 304."""

    # ``private``: behind a token the answer is for that client, not for a shared cache;
    # ``no-cache``: reused only after the server confirms its ETag (a new version of the
    # server may change the schema)
    _CACHE_CONTROL = "private, no-cache"

    def __init__(self, body: bytes) -> None:
        self.body = body
        self.etag = '"' + hashlib.sha256(body).hexdigest()[:32] + '"'

    @classmethod
    def of(cls, data: Any) -> _Cached:
        return cls(json.dumps(data, ensure_ascii=False, separators=(",", ":")).encode())

    def response(self, request: Request) -> Response:
        headers = {"ETag": self.etag, "Cache-Control": self._CACHE_CONTROL}
        asked = request.headers.get("if-none-match", "")
        # RFC 9110 13.1.2: a list of tags, weak ones compared by their opaque part, or "*"
        tags = {t.strip().removeprefix("W/") for t in asked.split(",")}
        if self.etag in tags or "*" in tags:
            return Response(status_code=304, headers=headers)
        return Response(self.body, media_type="application/json", headers=headers)


def _asset(name: str) -> Response:
    try:
        data = resources.files("motiontrack").joinpath("serve", "static", name).read_bytes()
    except OSError:
        return _error(404, "not found")
    return Response(data, media_type=_ASSETS[name], headers={"Cache-Control": "no-cache"})
