"""``motiontrack analyze``: scene analytics over an existing tracks file, as a :class:`Job`.

The source is the tracks file (:class:`TracksSource`: one :class:`TrackRows` per frame from 1 to
the file's last frame, frames without rows too: that is how tracks are forgotten and zone
occupancy averaged), the processor steps :class:`~motiontrack.analytics.Analytics` over each
(:class:`AnalyticsProcessor`), and the writers are those of ``track --scene``, so both commands
write the same files the same way. ``evaluate-events`` runs the same source and processor and
keeps the events in memory (:func:`analysed_events`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np

from ..analytics import Analytics, Scene
from ..classify import CLASS_NAMES, class_name
from ..errors import InputError, location
from ..io.sources import Source, SourceInfo
from ..types import Annotations, Event, FrameResult
from .analytics_writers import CountsWriter, EventsWriter
from .event_sinks import EventSinksWriter
from .event_store_writer import EventStoreWriter
from .folder import RunFolder
from .folders import source_name
from .heatmaps import HeatmapWriter, scene_geometry
from .job import Job, JobSummary

log = logging.getLogger(__name__)

__all__ = ["AnalyticsProcessor", "TrackRows", "TracksFrameResult", "TracksSource",
           "analysed_events", "analysis", "analyze_job", "analyze_tracks", "tracks_extent"]


def tracks_extent(tracks: Annotations) -> tuple[int, int]:
    """``(width, height)`` covering every box of ``tracks`` (at least 1 x 1 pixel)."""
    if not len(tracks):
        return 1, 1
    b = tracks.boxes
    return (max(1, int(math.ceil(float(np.max(b[:, 0] + b[:, 2]))))),
            max(1, int(math.ceil(float(np.max(b[:, 1] + b[:, 3]))))))


@dataclass(frozen=True)
class TrackRows:
    """The rows of one frame of a tracks file: ``ids`` (N,) int64, ``boxes`` (N, 4) float64
    ``x, y, w, h`` in pixels (N may be 0), ``labels`` (N,) the tracks' classes when the file
    has a class column (:mod:`motiontrack.classify`), else None."""

    frame: int
    ids: np.ndarray = field(repr=False)
    boxes: np.ndarray = field(repr=False)
    labels: np.ndarray | None = field(default=None, repr=False)


@dataclass(frozen=True)
class TracksFrameResult(FrameResult):
    """A frame of a tracks file analysed: no picture, no mask; the rows' boxes as they are in
    the file (:attr:`boxes`; a tracks file may hold boxes a :class:`~motiontrack.types.Track`
    refuses, such as zero-sized ones), the scene analytics of the frame in :attr:`scene`."""

    boxes: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)), repr=False)
    labels: np.ndarray | None = field(default=None, repr=False)

    def boxes_of(self, label: str) -> np.ndarray:
        """The rows' boxes of tracks of class ``label`` (none without a class column)."""
        if self.labels is None:
            return np.zeros((0, 4))
        return self.boxes[self.labels == label]


class TracksSource(Source):
    """A tracks file as a job's source: one :class:`TrackRows` per frame from 1 to its last.

    Parameters
    ----------
    tracks : the tracks (rows marked ``consider = 0`` are left out by :func:`analysis`).
    fps : the frame rate of the tracked video.
    size : ``(width, height)`` of its frames.
    name : what the tracks are (their file), for the summary and the events header.
    """

    def __init__(self, tracks: Annotations, fps: float, size: tuple[int, int],
                 name: str = "") -> None:
        super().__init__()
        self.tracks = tracks
        self.last = int(tracks.frames.max()) if len(tracks) else 0
        self.info = SourceInfo(name=str(name), width=int(size[0]), height=int(size[1]),
                               fps=fps, frame_count=self.last)

    def __iter__(self) -> Iterator[TrackRows]:  # type: ignore[override]
        t, rows = self.tracks, self.tracks.by_frame()
        empty_ids, empty = np.zeros(0, dtype=np.int64), np.zeros((0, 4))
        labels = None
        if len(t) and (t.classes >= 0).all():   # a tracks file with its tracks' classes
            labels = np.array([class_name(k) for k in t.classes.tolist()], dtype=object)
        for f in range(1, self.last + 1):
            idx = rows.get(f)
            yield (TrackRows(f, t.ids[idx], t.boxes[idx],
                             None if labels is None else labels[idx]) if idx is not None
                   else TrackRows(f, empty_ids, empty))


class AnalyticsProcessor:
    """Scene analytics stepped over every frame of a :class:`TracksSource`."""

    def __init__(self, analytics: Analytics) -> None:
        self.analytics = analytics

    def results(self, source: TracksSource) -> Iterator[TracksFrameResult]:
        fps = source.info.fps or 25.0
        for rows in source:
            scene = self.analytics.step(rows.frame, rows.ids, rows.boxes, labels=rows.labels)
            yield TracksFrameResult(index=rows.frame - 1, timestamp=(rows.frame - 1) / fps,
                                    frame=None, mask=None, regions=(), tracks=(), scene=scene,
                                    boxes=rows.boxes, labels=rows.labels)

    def annotate(self, result: FrameResult) -> np.ndarray:  # pragma: no cover - no video
        raise NotImplementedError("a tracks file has no pictures to annotate")

    def background(self) -> np.ndarray | None:
        return None

    def summary(self) -> dict[str, Any]:
        return {"analytics": self.analytics.summary()}


def analysis(tracks: Annotations, scene: Scene, fps: float, *, camera: Any = None,
             source: str = "", size: tuple[int, int] | None = None
             ) -> tuple[TracksSource, AnalyticsProcessor]:
    """The source and processor of analysing ``tracks`` with ``scene`` at ``fps``: the checks
    come first (a bad frame rate, rows without a track id), rows marked ``consider = 0``
    (ground truth's ignored objects) are left out; ``size`` defaults to the tracks' extent."""
    analytics = Analytics(scene, fps, camera)   # a bad frame rate fails before any file
    if len(tracks) and np.any(tracks.ids < 0):
        raise InputError(f"{location(source or 'tracks')}: rows without a track id (-1): "
                         "analytics needs tracks, not detections")
    ignored = int(np.count_nonzero(~tracks.consider))
    if ignored:
        log.info("leaving out %d rows marked consider = 0", ignored)
        tracks = tracks.select(tracks.consider)
    src = TracksSource(tracks, fps, size or tracks_extent(tracks), source)
    return src, AnalyticsProcessor(analytics)


def analysed_events(tracks: Annotations, scene: Scene, fps: float, *, camera: Any = None,
                    source: str = "") -> tuple[Event, ...]:
    """The events ``analyze`` writes for ``tracks``, in file order, without writing them."""
    src, proc = analysis(tracks, scene, fps, camera=camera, source=source)
    return tuple(e for r in proc.results(src) for e in r.scene.events)


def _layout(fps: float, tracks: int) -> Callable[[JobSummary], dict[str, Any]]:
    """``summary.json`` of an analysis: what was analysed, the analytics' and the heat map's
    entries, the outputs; the status when the run did not complete."""

    def layout(s: JobSummary) -> dict[str, Any]:
        d = {"source": s.source, "fps": float(fps), "frames": s.frames, "tracks": tracks,
             "analytics": s.extra["analytics"], "heatmap": s.extra.get("heatmap", {}),
             "outputs": s.outputs}
        if "sinks" in s.extra:   # webhooks and MQTT brokers: what each delivered, dropped, retried
            d["sinks"] = s.extra["sinks"]
        if "event_store" in s.extra:
            d["event_store"] = s.extra["event_store"]
        if s.status != "complete":
            d.update(status=s.status, interrupted=s.interrupted)
        return d

    return layout


def analyze_job(tracks: Annotations, scene: Scene, fps: float, out: str | Path, *,
                camera: Any = None, bin_s: float = 60.0, force: bool = False,
                source: str = "", size: tuple[int, int] | None = None,
                background: np.ndarray | None = None,
                sinks: EventSinksWriter | None = None, by_class: bool = False) -> Job:
    """The job writing ``events.jsonl``, ``events.db`` (no snapshots: a tracks file has no
    pictures), ``counts.csv``, ``heatmap.png`` (``heatmap_world.png`` with a camera) and
    ``summary.json`` for ``tracks`` in ``out``; ``by_class``: each class's line crossings in
    ``counts.csv`` and a heat map of each class (the file's class column).

    The heat map is ``size`` pixels (default: the extent of the tracks) over ``background``
    (default: black).
    """
    out = Path(out)
    src, proc = analysis(tracks, scene, fps, camera=camera, source=source, size=size)
    writers = [EventsWriter(out, source, scene.source),
               EventStoreWriter(RunFolder(out).event_store, source_name(source or out)),
               CountsWriter(out, scene.lines, scene.zones, bin_s, by_class=by_class)]
    if sinks is not None:
        writers.append(sinks)
    geometry = scene_geometry(scene.lines, scene.zones)
    writers.append(HeatmapWriter(out, scene.anchor, camera=camera, background=background,
                                 geometry=geometry, boxes_of=lambda r: r.boxes))
    if by_class:
        writers += [HeatmapWriter(out, scene.anchor, background=background, geometry=geometry,
                                  boxes_of=lambda r, c: r.boxes_of(c), label=c)
                    for c in CLASS_NAMES]
    n = int(len(np.unique(src.tracks.ids)))
    # the folder is often the tracked run's own: --force replaces the analysis, not its tracks
    return Job(src, proc, writers, out, force=force, layout=_layout(fps, n), replace_listed=False)


def analyze_tracks(tracks: Annotations, scene: Scene, fps: float, out: str | Path, *,
                   camera: Any = None, bin_s: float = 60.0, force: bool = False,
                   source: str = "", size: tuple[int, int] | None = None,
                   background: np.ndarray | None = None,
                   sinks: EventSinksWriter | None = None,
                   should_stop: Callable[[], bool] | None = None) -> dict[str, Any]:
    """Run :func:`analyze_job` and return the contents of its ``summary.json``; ``should_stop``
    as for :meth:`Job.run` (an interruption keeps the frames analysed and raises
    ``KeyboardInterrupt``)."""
    job = analyze_job(tracks, scene, fps, out, camera=camera, bin_s=bin_s, force=force,
                      source=source, size=size, background=background, sinks=sinks)
    return job.layout(job.run(should_stop=should_stop))
