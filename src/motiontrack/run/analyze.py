"""``motiontrack analyze``: scene analytics over an existing tracks file.

Every frame from 1 to the file's last frame is one step of
:class:`~motiontrack.analytics.Analytics` (frames without rows too: that is how tracks are
forgotten and zone occupancy averaged), written by the same writers as ``track --scene``.
"""

from __future__ import annotations

import json
import logging
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..analytics import Analytics, Scene
from ..errors import InputError, location
from ..io.atomic import atomic_write_text, check_writable
from ..io.mot import read_seqinfo
from ..types import Annotations
from .analytics_writers import CountsWriter, EventsWriter
from .event_sinks import EventSinksWriter
from .heatmaps import HeatmapWriter, scene_geometry

log = logging.getLogger(__name__)

__all__ = ["analyze_tracks", "frame_rate_beside", "frame_size_beside", "tracks_extent"]


def frame_rate_beside(tracks_path: str | Path) -> float | None:
    """The frame rate a tracks file's folder states: ``summary.json`` of the ``track`` run that
    wrote it (``source_fps``), or a MOTChallenge ``seqinfo.ini`` in its folder or the one above
    (``gt/gt.txt``); ``None`` when neither does."""
    folder = Path(tracks_path).resolve().parent
    summary = folder / "summary.json"
    if summary.is_file():
        try:
            fps = json.loads(summary.read_text(encoding="utf-8")).get("source_fps")
        except (OSError, ValueError, AttributeError):
            fps = None
        if isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0:
            return float(fps)
    for d in (folder, folder.parent):
        if (d / "seqinfo.ini").is_file():
            try:
                fps = read_seqinfo(d).get("framerate")   # the reader lower-cases keys
            except InputError:
                return None
            return float(fps) if isinstance(fps, (int, float)) and fps > 0 else None
    return None


def frame_size_beside(tracks_path: str | Path) -> tuple[int, int] | None:
    """``(width, height)`` of the frames a tracks file's folder states: ``summary.json`` of the
    ``track`` run that wrote it, or a MOTChallenge ``seqinfo.ini`` (``imWidth``, ``imHeight``)
    in its folder or the one above; ``None`` when neither does."""
    folder = Path(tracks_path).resolve().parent
    summary = folder / "summary.json"
    if summary.is_file():
        try:
            doc = json.loads(summary.read_text(encoding="utf-8"))
            w, h = doc.get("width"), doc.get("height")
        except (OSError, ValueError, AttributeError):
            w = h = None
        if isinstance(w, int) and isinstance(h, int) and w > 0 and h > 0:
            return w, h
    for d in (folder, folder.parent):
        if (d / "seqinfo.ini").is_file():
            try:
                info = read_seqinfo(d)
            except InputError:
                return None
            w, h = info.get("imwidth"), info.get("imheight")
            return (w, h) if isinstance(w, int) and isinstance(h, int) and w > 0 and h > 0 else None
    return None


def tracks_extent(tracks: Annotations) -> tuple[int, int]:
    """``(width, height)`` covering every box of ``tracks`` (at least 1 x 1 pixel)."""
    if not len(tracks):
        return 1, 1
    b = tracks.boxes
    return (max(1, int(math.ceil(float(np.max(b[:, 0] + b[:, 2]))))),
            max(1, int(math.ceil(float(np.max(b[:, 1] + b[:, 3]))))))


def analyze_tracks(tracks: Annotations, scene: Scene, fps: float, out: str | Path, *,
                   camera: Any = None, bin_s: float = 60.0, force: bool = False,
                   source: str = "", size: tuple[int, int] | None = None,
                   background: np.ndarray | None = None,
                   sinks: EventSinksWriter | None = None) -> dict[str, Any]:
    """Write ``events.jsonl``, ``counts.csv``, ``heatmap.png`` (``heatmap_world.png`` with a
    camera) and ``summary.json`` for ``tracks`` in ``out``.

    Rows marked ``consider = 0`` (ground truth's ignored objects) are left out. The heat map is
    ``size`` pixels (default: the extent of the tracks) over ``background`` (default: black).
    Returns the summary.
    """
    out = Path(out)
    analytics = Analytics(scene, fps, camera)   # a bad frame rate fails before any file
    if len(tracks) and np.any(tracks.ids < 0):
        raise InputError(f"{location(source or 'tracks')}: rows without a track id (-1): "
                         "analytics needs tracks, not detections")
    ignored = int(np.count_nonzero(~tracks.consider))
    if ignored:
        log.info("leaving out %d rows marked consider = 0", ignored)
        tracks = tracks.select(tracks.consider)
    events = EventsWriter(out, source, scene.source)
    counts = CountsWriter(out, scene.lines, scene.zones, bin_s)
    heat = HeatmapWriter(out, scene.anchor, size or tracks_extent(tracks), camera, background,
                         scene_geometry(scene.lines, scene.zones))
    writers = (events, counts) + ((sinks,) if sinks is not None else ())
    summary_path = out / "summary.json"
    check_writable([*events.paths.values(), *counts.paths.values(), *heat.paths.values(),
                    summary_path], force)
    rows = tracks.by_frame()
    last = int(tracks.frames.max()) if len(tracks) else 0
    empty = np.zeros((0, 4))
    keep = False
    for w in writers:
        w.open(fps)
    heat.open()
    try:
        for f in range(1, last + 1):
            idx = rows.get(f)
            ids, boxes = ((tracks.ids[idx], tracks.boxes[idx]) if idx is not None
                          else ((), empty))
            frame = analytics.step(f, ids, boxes)
            for w in writers:
                w.add(frame)
            heat.add_boxes(boxes)
        keep = True
    finally:
        for w in (*writers, heat):
            w.close(keep)
    summary = {"source": str(source), "fps": float(fps), "frames": last,
               "tracks": int(len(np.unique(tracks.ids))), "analytics": analytics.summary(),
               "heatmap": heat.info,
               "outputs": {k: str(p) for w in (*writers, heat) for k, p in w.paths.items()}}
    summary["outputs"]["summary"] = str(summary_path)
    if sinks is not None:   # webhooks and MQTT brokers: what each delivered, dropped, retried
        summary["sinks"] = sinks.stats()
    atomic_write_text(summary_path, json.dumps(summary, indent=2) + "\n")
    return summary
