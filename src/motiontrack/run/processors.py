"""Per-frame processors of a :class:`~motiontrack.run.job.Job`: what each command does to a frame.

* :class:`TrackProcessor` — the pipeline (motion or external detections → regions → tracks);
* :class:`FollowProcessor` — one object from a given box with a single-object tracker;
* :class:`SparseFlowProcessor` — Lucas–Kanade feature points grouped into objects;
* :class:`DenseFlowProcessor` — Farnebäck flow as a colour picture and a motion mask;
* :class:`OverlayProcessor` — ground truth and runs drawn on the frames, one colour each.

Each yields one :class:`~motiontrack.types.FrameResult` per frame and draws its own annotated
picture of it; the writers do the rest.
"""

from __future__ import annotations

from dataclasses import asdict, replace
from typing import TYPE_CHECKING, Any, Iterator, Sequence

import cv2
import numpy as np

from ..config import FarnebackParams, PipelineConfig
from ..io.sources import Source, SourceInfo
from ..pipeline import Pipeline
from ..render.annotate import annotate_frame, draw_label, frame_caption
from ..render.colors import TrackColors
from ..render.people import draw_people
from ..types import Annotations, Box, FrameResult, Track, TrackState, frame_number

if TYPE_CHECKING:
    # each processor imports the modules only it uses when it is made: a command loads what it
    # runs (``track`` without ``--scene`` neither analytics nor flow nor single trackers)
    from ..analytics import Analytics
    from ..tracking.flow import SparseFlowParams
    from ..tracking.single import SingleTracker

__all__ = ["TrackProcessor", "FollowProcessor", "SparseFlowProcessor", "DenseFlowProcessor",
           "OverlayProcessor"]

#: centre points kept for a followed object's trail
_FOLLOW_TRAIL = 64


def track_legend(cfg: PipelineConfig, external: bool = False) -> tuple[tuple[str, str], ...]:
    """The legend of ``track``'s annotated video: the kinds of boxes the run can draw."""
    entries = [("track", "track (id, trail)")]
    if cfg.tracker.output_lost:
        entries.append(("predicted", "track, not seen (predicted)"))
    entries.append(("region", "detection" if external else "motion region"))
    if cfg.people.enabled and not external:
        if cfg.people.heads:
            entries.append(("head", "head"))
        if cfg.people.hypotheses:
            entries.append(("hypothesis", "shape hypothesis"))
    return tuple(entries)


class TrackProcessor:
    """The pipeline on every frame (:meth:`~motiontrack.pipeline.Pipeline.results`).

    ``needs_background``: a writer reads the detector's background after each frame (the
    ``background`` intermediate movie), so detection of the next frame must not run meanwhile.
    """

    def __init__(self, cfg: PipelineConfig, info: SourceInfo,
                 detections: Annotations | None = None, needs_background: bool = False,
                 analytics: Analytics | None = None, camera: Any = None) -> None:
        self.cfg = cfg
        self.external = detections is not None
        self.analytics = analytics
        # every stage is built now: a bad plug-in name or ROI fails before anything is written
        # a scene with [abandoned] needs the recently stopped objects of the dual background
        self.pipe = Pipeline(cfg, (info.width, info.height), detections, info.fps,
                             static=analytics is not None and analytics.wants_static,
                             camera=camera)
        self.pipe.sequential = self.pipe.sequential or needs_background
        self.colors = TrackColors()
        self.legend = track_legend(cfg, self.external) if cfg.output.legend else ()

    def results(self, source: Source) -> Iterator[FrameResult]:
        if self.analytics is None:
            return self.pipe.results(source)
        return self._analysed(source)

    def _analysed(self, source: Source) -> Iterator[FrameResult]:
        """Scene analytics after the tracker, on the tracks each frame reports."""
        for result in self.pipe.results(source):
            # the boxes as tracks.txt stores them (2 decimals): `analyze` on that file then
            # sees exactly what this run saw and finds the same events
            boxes = np.array([float(f"{v:.2f}") for t in result.tracks
                              for v in t.box.as_array()]).reshape(-1, 4)
            labels = [t.label for t in result.tracks]
            scene = self.analytics.step(frame_number(result.index), [t.id for t in result.tracks],
                                        boxes, result.static, result.discontinuity,
                                        labels if any(labels) else None)
            yield replace(result, scene=scene)

    def annotate(self, result: FrameResult) -> np.ndarray:
        out = self.cfg.output
        colors = self.colors.assign(t.id for t in result.tracks)
        img = annotate_frame(result.frame, result.tracks, result.regions, result.mask, out.trail,
                             out.inset, inset_scale=out.inset_scale,
                             text=frame_caption(result.index), colors=colors, legend=self.legend)
        if self.pipe.people is not None and result.people is not None:
            draw_people(img, result.people, inplace=True, colors=colors)
        if self.analytics is not None:
            from ..render.scene import draw_scene

            draw_scene(img, self.analytics.scene.lines, self.analytics.scene.zones, result.scene)
        return img

    def background(self) -> np.ndarray | None:
        return self.pipe.detector.background() if self.pipe.detector is not None else None

    def summary(self) -> dict[str, Any]:
        # the scale detection ran at (``preprocess.scale = 0`` is resolved per frame size)
        out = {} if self.external else {"processing_scale": round(self.pipe.scale, 4)}
        if self.analytics is not None:
            out["analytics"] = self.analytics.summary()
        return out


class FollowProcessor:
    """A single-object tracker started on ``box`` in the first frame (id 1 in the tracks)."""

    def __init__(self, tracker: SingleTracker, box: Box, name: str,
                 params: dict[str, Any] | None = None) -> None:
        self.tracker = tracker
        self.box = box
        self.name = name
        self.params = dict(params or {})
        self.tracked = 0
        self._history: list[tuple[float, float]] = []
        self._label = ""
        self._colors = TrackColors()

    def results(self, source: Source) -> Iterator[FrameResult]:
        from ..tracking.single import follow

        for index, image, ok, box, score in follow(source, self.tracker, self.box):
            tracks: tuple[Track, ...] = ()
            if ok and box is not None:
                self.tracked += 1
                self._history.append(box.center)
                del self._history[:-_FOLLOW_TRAIL]
                tracks = (Track(id=1, box=box, state=TrackState.CONFIRMED, score=score,
                                history=tuple(self._history)),)
            self._label = f"{self.name} {score:.2f}" if ok else f"{self.name}: lost"
            yield FrameResult(index=index, timestamp=0.0, frame=image, mask=None, regions=(),
                              tracks=tracks)

    def annotate(self, result: FrameResult) -> np.ndarray:
        img = annotate_frame(result.frame, result.tracks, text=frame_caption(result.index),
                             colors=self._colors.assign(t.id for t in result.tracks))
        draw_label(img, self._label, (4, 4), (40, 40, 40) if result.tracks else (0, 0, 200),
                   scale=None)
        return img

    def background(self) -> np.ndarray | None:
        return None

    def summary(self) -> dict[str, Any]:
        b = self.box
        return {"tracker": self.name, "params": self.params, "box": [b.x, b.y, b.w, b.h],
                "frames_tracked": self.tracked}


class SparseFlowProcessor:
    """Shi–Tomasi features in moving regions followed by pyramidal Lucas–Kanade and grouped into
    objects (:class:`~motiontrack.tracking.flow.SparseFlowTracker`)."""

    def __init__(self, cfg: PipelineConfig, info: SourceInfo,
                 params: SparseFlowParams | None = None) -> None:
        from ..tracking.flow import SparseFlowParams, SparseFlowTracker

        self.cfg = cfg
        self.params = params or SparseFlowParams()
        self.tracker = SparseFlowTracker((info.width, info.height), self.params, cfg.motion,
                                         cfg.cleanup, cfg.regions, cfg.preprocess)
        self.colors = TrackColors()
        self.legend = ((("track", "object (id, trail)"), ("predicted", "object, not seen"),
                        ("points", "feature points")) if cfg.output.legend else ())

    def results(self, source: Source) -> Iterator[FrameResult]:
        for frame in source:
            tracks = self.tracker.update(frame.image)
            yield FrameResult(index=frame.index, timestamp=frame.timestamp, frame=frame.image,
                              mask=self.tracker.last_mask, regions=(), tracks=tuple(tracks))

    def annotate(self, result: FrameResult) -> np.ndarray:
        out = self.cfg.output
        colors = self.colors.assign(t.id for t in result.tracks)
        img = annotate_frame(result.frame, result.tracks, (), result.mask, out.trail, out.inset,
                             inset_scale=out.inset_scale, text=frame_caption(result.index),
                             colors=colors, legend=self.legend)
        from ..render.flow import draw_feature_trails

        draw_feature_trails(img, [tr for tr in self.tracker.trails() if tr[0] in colors], colors)
        return img

    def background(self) -> np.ndarray | None:
        return None

    def summary(self) -> dict[str, Any]:
        return {"mode": "sparse", "params": asdict(self.params)}


class DenseFlowProcessor:
    """Farnebäck flow of every frame: its colour picture (hue = direction, brightness =
    magnitude, :func:`~motiontrack.render.flow.flow_to_bgr`) is the annotated frame and its
    flow-magnitude mask the motion mask; magnitude statistics (px/frame, over all pixels of all
    frames after the first) go to the summary."""

    def __init__(self, params: FarnebackParams | None = None,
                 max_magnitude: float | None = None) -> None:
        from ..motion.dense_flow import DenseFlow

        self.params = params or FarnebackParams()
        self.max_magnitude = max_magnitude
        self.flow = DenseFlow(self.params)
        self._last: np.ndarray | None = None
        self._frames = 0
        self._total = 0.0
        self._count = 0
        self._moving = 0
        self._peak = 0.0

    def results(self, source: Source) -> Iterator[FrameResult]:
        for frame in source:
            flow, mask = self.flow.apply(frame.image)
            if self._frames > 0:
                self._measure(flow, mask)
            self._frames += 1
            self._last = flow
            yield FrameResult(index=frame.index, timestamp=frame.timestamp, frame=frame.image,
                              mask=mask, regions=(), tracks=())

    def _measure(self, flow: np.ndarray, mask: np.ndarray) -> None:
        mag = cv2.magnitude(flow[..., 0], flow[..., 1])
        self._total += float(mag.sum())
        self._count += mag.size
        self._peak = max(self._peak, float(mag.max()))
        self._moving += int(np.count_nonzero(mask))

    def annotate(self, result: FrameResult) -> np.ndarray:
        from ..render.flow import draw_flow_legend, flow_to_bgr

        img = flow_to_bgr(self._last, self.max_magnitude)
        top = self.max_magnitude
        if top is None:   # each frame at its own largest magnitude: the wheel's rim says which
            top = float(cv2.magnitude(self._last[..., 0], self._last[..., 1]).max())
        draw_flow_legend(img, top)
        draw_label(img, frame_caption(result.index), (4, img.shape[0] - 4), (40, 40, 40),
                   scale=None)
        return img

    def background(self) -> np.ndarray | None:
        return None

    def summary(self) -> dict[str, Any]:
        n = self._count
        return {"mode": "dense", "farneback": asdict(self.params),
                "max_magnitude": self.max_magnitude,
                "mean_magnitude": self._total / n if n else 0.0,
                "peak_magnitude": self._peak, "moving_fraction": self._moving / n if n else 0.0}


class OverlayProcessor:
    """Ground truth and runs (``(legend name, annotations)``) drawn over the frames numbered
    ``first`` to ``last`` (1-based, inclusive; ``last`` None = to the end)."""

    def __init__(self, runs: Sequence[tuple[str, Annotations]], gt: Annotations | None = None,
                 first: int = 1, last: int | None = None) -> None:
        from ..render.overlay import overlay_layers

        self.layers = overlay_layers(runs, gt)
        self.first, self.last = first, last

    def results(self, source: Source) -> Iterator[FrameResult]:
        for frame in source:
            f = frame_number(frame.index)
            if f < self.first:   # a ready-made Source ignores start/max_frames
                continue
            if self.last is not None and f > self.last:
                return
            yield FrameResult(index=frame.index, timestamp=frame.timestamp, frame=frame.image,
                              mask=None, regions=(), tracks=())

    def annotate(self, result: FrameResult) -> np.ndarray:
        from ..render.overlay import draw_overlay, layers_at

        return draw_overlay(result.frame, layers_at(self.layers, frame_number(result.index)),
                            frame_label=frame_caption(result.index))

    def background(self) -> np.ndarray | None:
        return None

    def summary(self) -> dict[str, Any]:
        return {"layers": [name for name, *_ in self.layers]}
