"""``motiontrack serve``: live cameras in the browser with their events (a driver over run/).

* :mod:`.cameras` — the cameras file → validated :class:`~.cameras.CameraSpec` values;
* :mod:`.worker` — one camera's process: ``track``'s job segment after segment, the picture,
  events and counts sent to the server;
* :mod:`.channel` — the bounded queues from a camera process to the server;
* :mod:`.hub` — the server's state per camera and the fan-out to viewers;
* :mod:`.scenes` — the scene files the editor reads and writes;
* :mod:`.app` — the Starlette app: page, JSON API, MJPEG and event streams;
* :mod:`.guard`, :mod:`.hosts` — who may ask the app what: token, host names, origins;
* :mod:`.server` — processes, supervision, uvicorn, shutdown.

Needs the ``serve`` extra (Starlette, uvicorn); nothing here is imported by ``import
motiontrack``. See ``docs/serve.md``.
"""
