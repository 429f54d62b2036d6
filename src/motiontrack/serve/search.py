"""The event store's search over HTTP: ``GET /api/events/search`` and ``/api/events/totals``.

``/api/events/{id}/snapshot.jpg``, ``object.jpg``, ``clip.avi`` give an event's evidence
(:mod:`motiontrack.run.evidence`); ``clip.mjpg`` replays its clip as MJPEG at the clip's rate
from where the event's own seconds start in it, which an ``<img>`` plays.

The same filters as ``motiontrack events`` (:func:`~motiontrack.io.event_store.query_from`):
``camera``, ``type``, ``rule``, ``class``, ``since``, ``until`` (ISO times or a time ago),
``limit`` (at most :data:`MAX_PAGE`, also the default) and ``offset``; newest first. Each
request opens the store read-only in a worker thread: a search never blocks the event loop
nor the cameras writing to the store.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, AsyncIterator

import anyio
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response, StreamingResponse
from starlette.routing import Route

from ..errors import MotionTrackError
from ..io.clips import clip_jpegs
from ..io.event_store import EventStore, query_from
from .mjpeg import MJPEG_TYPE, part

__all__ = ["search_routes", "MAX_PAGE"]

#: the most events one search answers with (page with ``offset``)
MAX_PAGE = 1000
_BINS = {"hour": 3600.0, "day": 86400.0}


def search_routes(store: Path | None) -> list[Route]:
    """The routes over the event store ``store`` (None, or not written yet: no events; an
    event's media then 404)."""

    def run(params: dict[str, str], totals: str | None) -> dict[str, Any]:
        query = query_from(params, time.time(), MAX_PAGE)
        if store is None or not store.is_file():   # no event yet
            return {"totals": []} if totals else {"events": [], "total": 0,
                                                   "limit": query.limit, "offset": query.offset}
        with EventStore(store, readonly=True) as s:
            if totals:
                offset = time.localtime().tm_gmtoff
                return {"totals": [{"camera": c, "start": start, "type": t, "count": n}
                                   for c, start, t, n in s.totals(_BINS[totals], query, offset)]}
            return {"events": [e.as_dict() for e in s.search(query)], "total": s.count(query),
                    "limit": query.limit, "offset": query.offset}

    async def answer(request: Request, totals: str | None = None) -> Response:
        params = dict(request.query_params)
        params.pop("bin", None)
        params.pop("token", None)   # the token check's, when a page sends it in the query
        try:
            return JSONResponse(await anyio.to_thread.run_sync(run, params, totals))
        except MotionTrackError as exc:
            return JSONResponse({"error": str(exc)}, status_code=400)

    async def search(request: Request) -> Response:
        return await answer(request)

    async def totals(request: Request) -> Response:
        kind = request.query_params.get("bin", "hour")
        if kind not in _BINS:
            return JSONResponse({"error": "bin must be hour or day"}, status_code=400)
        return await answer(request, kind)

    def media_path(event_id: int, kind: str) -> tuple[Path | None, float]:
        """The file of ``kind`` (snapshot, object, clip) of event ``event_id``, inside the
        store's folder, or None; and the event's ``clip_offset`` (0 without one)."""
        if store is None or not store.is_file():
            return None, 0.0
        with EventStore(store, readonly=True) as s:
            row = s.get(event_id)
        if row is None:
            return None, 0.0
        rel = row.clip if kind == "clip" else row.snapshot
        if rel is None:
            return None, 0.0
        if kind == "object":
            rel = rel[:-len(".jpg")] + "-object.jpg"
        root = store.parent.resolve()
        path = (root / rel).resolve()
        found = path if path.is_relative_to(root) and path.is_file() else None
        return found, float(row.clip_offset or 0.0)

    async def media(request: Request) -> Response:
        kind = request.path_params["kind"]
        if kind not in _MEDIA:
            return JSONResponse({"error": f"no such file: {', '.join(_MEDIA)}"}, status_code=404)
        try:
            event_id = int(request.path_params["id"])
        except ValueError:
            return JSONResponse({"error": "the event id must be a number"}, status_code=400)
        path, offset = await anyio.to_thread.run_sync(media_path, event_id, _MEDIA[kind][0])
        if path is None:
            return JSONResponse({"error": f"no {kind} for this event"}, status_code=404)
        if kind == "clip.mjpg":   # from where the event's own seconds start in a shared clip
            return StreamingResponse(_replay(path, offset), media_type=MJPEG_TYPE)
        return FileResponse(path, media_type=_MEDIA[kind][1])

    return [Route("/api/events/search", search), Route("/api/events/totals", totals),
            Route("/api/events/{id}/{kind:str}", media)]


#: the media of an event: what the URL names → (the file it comes from, its content type)
_MEDIA = {"snapshot.jpg": ("snapshot", "image/jpeg"), "object.jpg": ("object", "image/jpeg"),
          "clip.avi": ("clip", "video/x-msvideo"), "clip.mjpg": ("clip", "")}


async def _replay(path: Path, start_s: float = 0.0) -> AsyncIterator[bytes]:
    """A clip's JPEG frames from ``start_s`` seconds into it, as an MJPEG stream at the clip's
    own rate: an ``<img>`` plays it."""
    frames, fps = await anyio.to_thread.run_sync(clip_jpegs, path)
    for jpeg in frames[int(round(start_s * fps)) if fps > 0 else 0:]:
        yield part(jpeg)
        await anyio.sleep(1.0 / fps if fps > 0 else 0.1)
