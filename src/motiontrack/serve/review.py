"""``motiontrack serve --review DIR``: the review page over a finished run's event store.

A ``track --scene`` run folder, a ``batch`` results folder or a ``serve`` output folder holds an
``events.db`` (:mod:`motiontrack.io.event_store`) and the snapshots and clips it names; this
serves the review page (``/``) and the event search and media of that store, read-only, with no
camera. The same host, token and ``--allowed-host`` rules as ``serve`` apply.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Sequence

from ..errors import InputError
from ..io.event_store import EventStore, store_path
from .app import create_app
from .hosts import allowed_hosts
from .hub import Hub
from .server import check_port

log = logging.getLogger(__name__)

__all__ = ["review"]


def review(folder: str | Path, host: str = "127.0.0.1", port: int = 8080,
           token: str | None = None, allowed: Sequence[str] = ()) -> int:
    """Serve the review page of the store in ``folder`` until SIGINT or SIGTERM; 0."""
    import uvicorn

    hosts = allowed_hosts(host, allowed)
    store = store_path(folder)
    if not store.is_file():
        raise InputError(f"no event store at {store} (a track --scene, batch or serve output "
                         "folder has one)")
    with EventStore(store, readonly=True) as s:   # a file that is not a store fails here
        n = s.count()
    check_port(host, port)
    app = create_app(Hub([]), token, hosts=hosts, store=store, review_only=True)
    config = uvicorn.Config(app, host=host, port=port, log_level="warning", lifespan="off",
                            access_log=False)
    log.info("reviewing %d events of %s on http://%s:%d/", n, store, host, port)
    uvicorn.Server(config).run()
    return 0
