"""The event store's search over HTTP: ``GET /api/events/search`` and ``/api/events/totals``.

The same filters as ``motiontrack events`` (:func:`~motiontrack.io.event_store.query_from`):
``camera``, ``type``, ``rule``, ``class``, ``since``, ``until`` (ISO times or a time ago),
``limit`` (at most :data:`MAX_PAGE`, also the default) and ``offset``; newest first. Each
request opens the store read-only in a worker thread: a search never blocks the event loop
nor the cameras writing to the store.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import anyio
from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.routing import Route

from ..errors import MotionTrackError
from ..io.event_store import EventStore, query_from

__all__ = ["search_routes", "MAX_PAGE"]

#: the most events one search answers with (page with ``offset``)
MAX_PAGE = 1000
_BINS = {"hour": 3600.0, "day": 86400.0}


def search_routes(store: Path | None) -> list[Route]:
    """The routes over the event store ``store`` (None: the app has none, 404)."""

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

    return [Route("/api/events/search", search), Route("/api/events/totals", totals)]
