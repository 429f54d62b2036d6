"""The pipeline: the only module that knows the stage order.

    source → preprocess → motion (mask) → clean-up → regions → [detector] → [people] → tracker
           → [classes] → FrameResult

``[detector]`` is the user's ONNX model (``detector.model``: its boxes join or replace the
regions), ``[classes]`` the track classifier (``classes.enabled``: a class per track).

A frame that carries a :class:`~motiontrack.types.Discontinuity` (the source looped,
reconnected, or was positioned at a start frame) resets every stage before it is processed
(:meth:`Pipeline.reset`): the motion and background models learn afresh (with the warm-up
again), the tracker ends its tracks, and the result carries the mark on to the analytics and
the writers.

:class:`Pipeline` holds every stage's state and processes frames; :func:`run` is the Python API
(:func:`motiontrack.track`): a :class:`TrackRun` that yields one
:class:`~motiontrack.types.FrameResult` per frame. Writing outputs is the run layer's work
(:mod:`motiontrack.run`).
"""

from __future__ import annotations

import atexit
import itertools
import logging
import statistics
import weakref
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable, Iterator, NamedTuple

import cv2
import numpy as np

from . import synth as _synth  # noqa: F401  (registers the synth: sources)
from .classify import TrackClassifier
from .classify.scene_kind import VehicleScene
from .config import MotionConfig, PipelineConfig, SourceConfig, load_config, warn_if_oversized
from .detect import create as create_detector_model
from .detect import detector_regions
from .imaging import pixel_window, resolve_scale, scaled_size
from .io.imagesize import too_many_pixels
from .io.sources import Source, open_source, prefetch
from .motion import create_detector
from .motion.cleanup import clean_mask
from .motion.ghosts import GhostFilter
from .motion.stage import MotionStage
from .motion.static import DualBackground
from .motion.regions import find_regions, silhouettes, smallest_region
from .people import PeopleStage, head_params
from .people.heads import split_regions_by_heads
from .preprocess import load_roi, preprocess
from .tracking import detections as _detections  # noqa: F401  (registers tracker "detections")
from .tracking.association import intersections, iou_matrix
from .tracking.bridge import Bridge
from .tracking.tracker import TRACKERS
from .types import (Annotations, Box, Discontinuity, Frame, FrameResult, PeopleFrame, Region,
                    StaticFrame, frame_number)

log = logging.getLogger(__name__)

__all__ = ["Pipeline", "run", "TrackRun", "resolve_config", "completes_tracks",
           "fill_gap_frames", "open_configured_source", "fitted_camera"]


#: ``people.auto_split``: weight of each frame's median region height/width in the scene's
#: running mean, and the fraction of that mean below which a region is searched for heads
_SCENE_RATE = 0.05
_WIDE = 0.75


def resolve_config(config: PipelineConfig | str | Path | None) -> PipelineConfig:
    if config is None:
        return PipelineConfig()
    if isinstance(config, PipelineConfig):
        return config
    return load_config(config)


def _regions_from_detections(det: Annotations, rows: np.ndarray | None) -> list[Region]:
    if rows is None or len(rows) == 0:
        return []
    out = []
    for i in rows:
        x, y, w, h = det.boxes[i]
        if w <= 0 or h <= 0:
            continue
        out.append(Region(box=Box(float(x), float(y), float(w), float(h)),
                          centroid=(float(x + w / 2), float(y + h / 2)), area=float(w * h),
                          score=float(det.scores[i])))
    return out


def _ghost_filter(motion: MotionConfig) -> GhostFilter:
    """The ghost filter of ``motion``'s settings (its light test included)."""
    return GhostFilter(motion.ghost_ratio, pixels=motion.ghost_pixels,
                       lit=(motion.light_share, motion.light_gain))


def completes_tracks(cfg: PipelineConfig, external: bool) -> bool:
    """Whether a run's tracks get their tentative frames (``tracker.backfill``) and their gaps
    filled (``tracker.fill_gaps_s``): tracks from external detections, or from motion regions with
    ``tracker.fill_motion``."""
    return external or cfg.tracker.fill_motion


def fill_gap_frames(cfg: PipelineConfig, fps: float | None, external: bool) -> int:
    """Longest gap (frames) of a track that the tracks writer fills by interpolation in
    ``tracks.txt`` (0 = none): ``tracker.fill_gaps_s`` at the source's frame rate (25 fps when
    unknown), when :func:`completes_tracks`. See :func:`motiontrack.tracking.gaps.fill_gaps`."""
    if not completes_tracks(cfg, external):
        return 0
    return int(round(cfg.tracker.fill_gaps_s * (fps or 25.0)))


@dataclass(frozen=True)
class Motion:
    """The image work of one frame (:meth:`Pipeline.motion`): the cleaned motion ``mask`` and
    the detector's ``raw_mask`` at processing scale, the preprocessed frame ``small`` they came
    from, the ``static`` foreground when the pipeline keeps a dual background, the detector's
    ``background`` image after this frame when a later stage reads it (the people stage's
    shapes); with external detections only ``detections`` (``mask`` is None)."""

    mask: np.ndarray | None
    raw_mask: np.ndarray | None = None
    small: np.ndarray | None = None
    detections: list[Region] = field(default_factory=list)
    static: StaticFrame | None = None
    background: np.ndarray | None = None
    #: the frame's discontinuity: the models were reset before it
    discontinuity: Discontinuity | None = None
    #: the background model re-learnt at this frame after a sudden change of the whole picture
    relearned: bool = False
    #: the first background the model re-learnt from at this frame (``motion.bootstrap_s``)
    seed: np.ndarray | None = None
    #: the camera's motion since the previous frame while it moves ((2, 3), previous frame's
    #: pixels → this frame's, processing scale): the tracker carries its tracks with it
    step: np.ndarray | None = None
    #: pixels of ``raw_mask`` the detector holds for a stopped tracked object (uint8 0/255, or
    #: None): the ghost filter does not take them
    held: np.ndarray | None = None


class Feedback(NamedTuple):
    """What the tracks ask of the motion detector for a frame (:meth:`Pipeline.feedback`)."""

    protect: np.ndarray | None
    relearn: np.ndarray | None
    #: the scene's recent tracks are mostly vehicles (None: the detector does not ask)
    vehicles: bool | None = None


@dataclass(frozen=True)
class Detection:
    """The motion stage's result for one frame (:meth:`Pipeline.detect`): its :class:`Motion`,
    the mask the regions were found in (the ghost filter may clear parts of it), the regions,
    and the heads ``people.auto_split`` found (None when it searched no region)."""

    motion: Motion
    mask: np.ndarray | None
    regions: list[Region]
    heads: tuple | None = None


class Pipeline:
    """Per-frame processing with all stage state (background model, tracker).

    Parameters
    ----------
    cfg : PipelineConfig
    image_size : (width, height) of the source frames.
    detections : optional external detections (MOTChallenge det rows, 1-based frames); when given
        they replace the motion stage.
    fps : the source's frame rate (None = unknown, taken as 25): converts durations in seconds
        (``tracker.max_lost_s``) to frames.
    camera : a camera model fitted to the source: the track classifier measures in metres.
    static : keep a dual background (:class:`~motiontrack.motion.static.DualBackground`) and
        report each frame's recently stopped objects (``FrameResult.static``); only with the
        motion stage (not with external detections). It does not change the tracks.
    """

    def __init__(self, cfg: PipelineConfig, image_size: tuple[int, int],
                 detections: Annotations | None = None, fps: float | None = None,
                 static: bool = False, camera: Any = None) -> None:
        self.cfg = cfg
        self._min_gap: float | None = None   # shortest time between frames seen: one period
        self._last_ts: float | None = None
        self.image_size = image_size
        self.scale = resolve_scale(cfg.preprocess.scale, *image_size)
        #: components of the mask smaller than this (processing pixels) are no region
        self._speck = smallest_region(cfg.regions, self.scale, image_size)
        self.detections = detections
        self._det_index = detections.by_frame() if detections is not None else None
        self.fps = fps
        #: the motion stage: detector, camera-motion compensation, sudden-change handling
        self.stage = (MotionStage(create_detector(cfg.motion, fps), cfg.motion, cfg.stabilize,
                                  fps) if detections is None else None)
        pre = cfg.preprocess
        if self.detector is not None and self.detector.wants_color and pre.grayscale:
            pre = replace(pre, grayscale=False)
        self.pre_cfg = replace(pre, scale=self.scale)  # the resolved (automatic) scale
        pw, ph = scaled_size(image_size[0], image_size[1], self.scale)
        self.roi = load_roi(pre.roi, pw, ph, cfg.source.max_pixels) if pre.roi else None
        self._init_tracker(cfg, image_size, detections, fps)
        self._init_stages(cfg, fps, camera, static)
        #: frames a lost track may coast: its stopped pixels are kept that long
        self._keep_unseen = self.tracker.max_lost
        #: the previous frame's feedback to a detector that takes it (``relearns``): the ghost
        #: filter's ghost pixels to re-learn, and the static objects not to learn
        self._relearn: np.ndarray | None = None
        self._static_prev: StaticFrame | None = None
        #: the static objects the hold kept in the last protect mask (boxes)
        self._held_static: list[np.ndarray] = []
        #: the last frame given feedback carried a discontinuity (two-thread order)
        self._fed_cut = False
        #: feedback is made right before each frame's detection (one thread), not a frame ahead
        self.sequential_feedback = True
        self.frames_seen = 0
        #: the run's frame count (``index`` of :meth:`regions_of`) at the last reset: the
        #: warm-up counts from there
        self._warm_from = 0
        #: regions are ignored before this frame count (after a sudden change)
        self._quiet_until = 0
        #: the people stage's shapes read the detector's background image of each frame: it is
        #: taken right after the detector's update, in the detector's thread, and travels with
        #: the frame's Motion, so detection of the next frame can run meanwhile
        self._wants_background = (self.people is not None and self.people.needs_background
                                  and self.detector is not None)
        #: run detection and tracking in one thread (needed when a later stage reads the
        #: detector's state for the same frame: a writer of the background image). Head-based
        #: splitting and the people stage need only what Motion carries: they run in this thread
        #: while the worker detects the next frame (measured faster than running head splitting
        #: in the worker, which it would slow down).
        self.sequential = False

    def _init_tracker(self, cfg: PipelineConfig, image_size: tuple[int, int],
                      detections: Annotations | None, fps: float | None) -> None:
        """The tracker, as ``tracker.method`` says."""
        tracker_cfg = cfg.tracker
        if detections is not None:
            # a detector's box is one object: there is no merged blob to split (split shares of a
            # box that overlaps a neighbour's prediction swap identities; benchmarks/detections_pets.py),
            # and no fragment at an occluder's edge to tilt the Kalman velocity (coasting at the
            # median pace there: HOTA the same in sum over the benchmark's rows, MOTA -0.028
            # with 20% dropped boxes)
            tracker_cfg = replace(tracker_cfg, split_merged=False, absorb_pieces=False,
                                  coast_frames=0)
        self.tracker = TRACKERS.get(cfg.tracker.method)(tracker_cfg, image_size, fps)
        #: the tracker weighs the appearance of external detections in the frame's picture
        self.tracker_sees_pictures = isinstance(self.tracker, _detections.DetectionTracker)
        #: a confirmed track's tentative frames are reported (FrameResult.earlier)
        self._report_earlier = (cfg.tracker.backfill
                                and completes_tracks(cfg, detections is not None))
        # the tracker keeps them for that, and for the classes: a track's class is decided from
        # its tentative frames too, so its first events carry it (docs/classes.md)
        self.tracker.keep_tentative = self._report_earlier or cfg.classes.enabled

    def _init_stages(self, cfg: PipelineConfig, fps: float | None, camera: Any,
                     static: bool) -> None:
        """The stages around the tracker: the user's detector, the classes, the people stage,
        head splitting, the ghost filter, the bridge and the dual background."""
        #: the user's detector (``detector.model``): its boxes join or replace the regions
        self.onnx = None
        if cfg.detector.model:
            d = cfg.detector
            self.onnx = create_detector_model(d.model, names=d.names, input_size=d.input_size,
                                              score=d.score, nms=d.nms)
        #: the class of each track (``classes.enabled``), after the tracker
        self.classes = (TrackClassifier(cfg.classes, fps, camera) if cfg.classes.enabled
                        else None)
        self.people = None
        if cfg.people.enabled:
            self.people = PeopleStage(cfg.people)
        #: head detector settings for ``people.auto_split`` (None = off): merged regions are split
        #: between heads, with the people stage off, while the scene's regions are upright
        self.auto_heads: dict[str, float] | None = None
        if (not cfg.people.enabled and cfg.people.auto_split and cfg.people.heads
                and cfg.people.split and self.detector is not None):
            self.auto_heads = head_params(cfg.people)
        self._upright: float | None = None   # running mean of the frames' median region h/w
        self.ghosts = None
        if cfg.motion.ghost_ratio > 0 and self.detector is not None and not self.detector.own_ghosts:
            self.ghosts = _ghost_filter(cfg.motion)
        self._prev_tracks: tuple = ()
        #: whether the recent tracks are mostly vehicles, for a detector whose shadow test
        #: depends on it and for the reported silhouettes (None: not asked)
        self._scene_kind = (VehicleScene() if self.classes is not None and self.detector is not None
                            and (self.detector.switches_shadows or cfg.regions.silhouettes)
                            else None)
        self._vehicles: bool | None = False if self._scene_kind is not None else None
        self.bridge = None
        if cfg.tracker.bridge != "none" and not self.tracker_sees_pictures:
            # (the detection tracker takes no owned measurements: tracker.bridge needs kalman)
            self.bridge = Bridge(cfg.tracker.bridge, cfg.tracker.bridge_frames)
        #: the dual background: for FrameResult.static (``static``) and motion.keep_stopped
        self.static = (DualBackground(fps or 25.0, self.scale)
                       if (static or cfg.motion.keep_stopped) and self.detector is not None
                       else None)
        self.report_static = static
        self.keep_stopped = cfg.motion.keep_stopped and self.static is not None

    @property
    def detector(self):
        """The motion detector (None with external detections)."""
        return self.stage.detector if self.stage is not None else None

    def reset(self, discontinuity: Discontinuity) -> None:
        """Every stage's state after ``discontinuity``, in the order a frame meets them:
        :meth:`reset_motion` (image work), :meth:`reset_regions`, :meth:`reset_tracking`.
        :meth:`results` calls each in the thread that runs its stage when a frame carries one."""
        log.info("source discontinuity (%s): models and tracks reset", discontinuity.reason)
        self.reset_motion()
        self.reset_regions(self.frames_seen)
        self.reset_tracking()

    def reset_motion(self) -> None:
        """New motion and dual-background models: they re-learn the scene from the next frame
        (a model of the frames before a jump would see the whole picture change)."""
        if self.stage is not None:
            self.stage.reset(create_detector(self.cfg.motion, self.fps))
        self._static_prev = None
        self._held_static = []
        if self.static is not None:
            self.static = DualBackground(self.static.fps, self.scale)

    def reset_regions(self, index: int) -> None:
        """The ghost filter's background afresh, and the warm-up counted again from ``index``."""
        if self.ghosts is not None:
            self.ghosts = _ghost_filter(self.cfg.motion)
        self._warm_from = index
        self._quiet_until = 0

    def reset_tracking(self) -> None:
        """The tracker ends every track (ids keep counting); the bridge and the people stage
        forget theirs; the gap to the next frame is not a gap."""
        self.tracker.reset()
        if self.classes is not None:
            self.classes.reset()
        if self.bridge is not None:
            self.bridge = Bridge(self.cfg.tracker.bridge, self.cfg.tracker.bridge_frames)
        if self.people is not None:
            self.people.reset()
        self._prev_tracks = ()
        self._last_ts = None
        if self._scene_kind is not None:
            self._scene_kind.reset()
            self._vehicles = False
            self.tracker.vehicles = False

    def _frame_gap(self, frame: Frame) -> int:
        """Frame periods since the previous frame, from the timestamps (wall-clock for live
        sources), so the tracker sees gaps such as a camera that dropped and reconnected.

        The period is learnt as the shortest gap seen so far rather than taken from the source's
        nominal rate, which cameras often misreport."""
        last, self._last_ts = self._last_ts, frame.timestamp
        if last is None or frame.timestamp <= last:
            return 1
        gap = frame.timestamp - last
        self._min_gap = gap if self._min_gap is None else min(self._min_gap, gap)
        return max(1, int(round(gap / self._min_gap)))

    def feedback(self, frame: Frame, small: np.ndarray) -> Feedback:
        """What the tracks and the ghost filter ask of the detector for ``frame`` (preprocessed
        ``small``): ``(protect, relearn, vehicles)``, the pixels not to learn and those to
        re-learn at once (:meth:`MotionDetector.apply`), from the state they are in now, and
        whether the scene's tracks are mostly vehicles (:meth:`MotionDetector.vehicle_scene`;
        None when the detector does not ask). The masks are None for a frame after a
        discontinuity (the tracks before a jump say nothing of where it moves), and for the frame
        after it in :meth:`results`' two-thread order, whose state is still that of the frames
        before the jump."""
        relearn, self._relearn = self._relearn, None
        vehicles = self._vehicles
        if frame.discontinuity is not None or self._fed_cut:
            self._fed_cut = frame.discontinuity is not None and not self.sequential_feedback
            return Feedback(None, None, vehicles)
        protect = self._protect_mask(small.shape[:2])
        return Feedback(protect, relearn if self.detector.relearns else None, vehicles)

    def _protect_mask(self, shape: tuple[int, int]) -> np.ndarray | None:
        """Pixels (processing scale) not learnt as background: where the previous frame's
        confirmed tracks that have moved are expected (those slower than the detector's
        ``protect_speed`` only, when it has one), and the previous frame's static objects (with
        a dual background and a detector that re-learns)."""
        if not self.detector.protect:
            return None
        speed = self.detector.protect_speed
        slower = speed / (self.fps or 25.0) if speed is not None else None
        boxes = list(self.tracker.moving_boxes(slower=slower))
        static = self._static_prev
        if static is not None and self.detector.relearns:
            boxes += self._static_held(static)
        if not boxes:
            return None
        mask = np.zeros(shape, bool)
        for box in boxes:
            x1, y1, x2, y2 = pixel_window(box, self.scale, shape)
            if x2 > x1 and y2 > y1:
                mask[y1:y2, x1:x2] = True
        return mask

    def _static_held(self, static: StaticFrame) -> list[np.ndarray]:
        """The static objects the hold keeps: those at least half covered by a named track's box
        (something tracked that stopped), and those that overlap one kept the frame before (a
        bag after its owner walked off). A static object no track brought is a change of the
        background, such as the place a person stood in the first frame: it is learnt."""
        tracks = self.tracker.named_boxes()
        kept = np.array(self._held_static).reshape(-1, 4)
        held = []
        for o in static.objects:
            b = o.box.as_array()
            # the largest share of the object one track's box covers
            cover = intersections(b, tracks).max(initial=0.0) / max(b[2] * b[3], 1e-9)
            if cover >= 0.5 or (len(kept) and iou_matrix(b[None], kept).max() >= 0.3):
                held.append(b)
        self._held_static = held
        return held

    def detect(self, frame: Frame, index: int, small: np.ndarray | None = None) -> Detection:
        """Motion stage of one frame. ``index`` counts frames from the start of this run (for
        the warm-up); ``small`` is :meth:`prepare`'s image of the frame when already made."""
        return self.regions_of(index, self.motion(frame, small))

    def prepare(self, frame: Frame) -> np.ndarray | None:
        """The frame at processing scale, preprocessed (None with external detections): the
        part of the image work that needs nothing but the frame, so a source that decodes
        ahead can do it in its thread (:meth:`~motiontrack.io.sources.Source.prepared`)."""
        return preprocess(frame.image, self.pre_cfg) if self.detector is not None else None

    def motion(self, frame: Frame, small: np.ndarray | None = None,
               feedback: Feedback | None = None) -> Motion:
        """First half of :meth:`detect`, the image work (OpenCV, which releases the GIL).
        ``feedback``: the detector's :class:`Feedback` made beforehand by :meth:`feedback`
        (None: made here from the tracks and ghosts as they are now)."""
        cut = frame.discontinuity
        if self._det_index is not None:
            return Motion(None, detections=_regions_from_detections(
                self.detections, self._det_index.get(frame_number(frame.index))),
                discontinuity=cut)
        if small is None:
            small = self.prepare(frame)
        if feedback is None:
            feedback = self.feedback(frame, small)
        if cut is not None:
            self.reset_motion()
        protect, relearn, vehicles = feedback
        if vehicles is not None:
            self.detector.vehicle_scene(vehicles)
        out = self.stage.apply(small, protect, relearn)
        raw = out.raw
        if self.roi is not None:
            raw = np.bitwise_and(raw, self.roi)
        if self.static is not None and (out.relearned or out.reanchored):
            self.static = DualBackground(self.static.fps, self.scale)
        static = self.static.apply(out.view) if self.static is not None else None
        self._static_prev = static
        background = self.detector.background() if self._wants_background else None
        return Motion(clean_mask(raw, self.cfg.cleanup), raw_mask=raw, small=small, static=static,
                      background=background, discontinuity=cut, relearned=out.relearned,
                      seed=out.seed,
                      step=out.step, held=out.held)

    def regions_of(self, index: int, motion: Motion) -> Detection:
        """Second half of :meth:`detect`: the mask's regions, split between heads while the
        scene is upright (``people.auto_split``)."""
        mask = motion.mask
        if motion.discontinuity is not None:
            self.reset_regions(index)
        if mask is None:
            return Detection(motion, None, motion.detections)
        if self.keep_stopped:
            mask = self._keep_stopped(mask, motion.static)
        if self.ghosts is not None:   # it learns its background in the warm-up frames too
            mask, regions = self.ghosts.regions(motion.small, mask, self._find, self.scale,
                                                keep=motion.held)
            if self.detector.relearns:
                # the detector re-learns the ghost pixels with the next frame
                self._relearn = self.ghosts.ghost_pixels(mask.shape[:2])
        else:
            regions = self._find(mask)
        if motion.relearned:
            self._quiet_until = index + self.cfg.motion.relearn_frames
        if motion.seed is not None and self.ghosts is not None:
            self.ghosts.seed(motion.seed)
        if index - self._warm_from < self.cfg.motion.warmup or index < self._quiet_until:
            regions = []
        heads = None
        if regions:
            regions, heads = self._split_upright(mask, regions)
        return Detection(motion, mask, regions, heads)

    def _keep_stopped(self, mask: np.ndarray, static: StaticFrame | None) -> np.ndarray:
        """``motion.keep_stopped``: the mask plus the static foreground that lies both in a
        static object (ghosts are left out) and in the box of a track that has moved (where the
        tracker expects it; lost tracks too, up to ``tracker.max_lost_s``). A person who stops
        fades into the motion detector's background within a second or two, while the dual
        background's long-term model keeps them as foreground for tens of seconds."""
        if static is None or static.mask is None or not static.objects:
            return mask
        boxes = self.tracker.moving_boxes(unseen=self._keep_unseen)
        if not len(boxes):
            return mask
        shape = mask.shape[:2]
        near = np.zeros(shape, np.uint8)
        for box in boxes:
            x1, y1, x2, y2 = pixel_window(box, self.scale, shape)
            near[y1:y2, x1:x2] = 255
        objects = np.zeros(shape, np.uint8)
        for obj in static.objects:
            x1, y1, x2, y2 = pixel_window(obj.box.as_array(), self.scale, shape)
            objects[y1:y2, x1:x2] = 255
        held = cv2.bitwise_and(cv2.bitwise_and(static.mask, near), objects)
        return cv2.bitwise_or(mask, held)

    def _find(self, mask: np.ndarray) -> list[Region]:
        return find_regions(mask, self.cfg.regions, self.scale, self.image_size)

    def _split_upright(self, mask: np.ndarray, regions: list[Region]
                       ) -> tuple[list[Region], tuple | None]:
        """``people.auto_split``: while the scene's regions are upright (a running mean of each
        frame's median height/width at least ``people.upright_ratio``: people, not cars), split
        every region clearly wider than that typical shape between the heads found in it.
        Returns the regions and the heads found (None when no region was searched)."""
        if self.auto_heads is None:
            return regions, None
        ratio = self.cfg.people.upright_ratio
        shapes = [r.box.h / r.box.w for r in regions]
        shape = float(statistics.median(shapes))   # a tenth of np.median's cost on a short list
        self._upright = (shape if self._upright is None
                         else (1 - _SCENE_RATE) * self._upright + _SCENE_RATE * shape)
        if self._upright < ratio:
            return regions, None
        # searched for heads: regions a third wider than the scene's typical one (a lone person
        # is left alone; two people side by side are twice as wide)
        wide = [s < _WIDE * self._upright for s in shapes]
        if not any(wide):
            return regions, None
        regions, heads = split_regions_by_heads(
            mask, regions, mask.shape[1] / self.image_size[0], search=wide, **self.auto_heads)
        return regions, tuple(heads)

    def track(self, frame: Frame, det: Detection) -> FrameResult:
        """Tracking stage of one frame, after :meth:`detect` (and the people stage, when on)."""
        regions, mask, small = det.regions, det.mask, det.motion.small
        if frame.discontinuity is not None:
            if self.frames_seen:   # (a run's first frame has nothing to reset)
                log.info("frame %d: source discontinuity (%s): models and tracks reset",
                         frame.index, frame.discontinuity.reason)
            self.reset_tracking()
        dets = None
        if self.onnx is not None:
            regions, dets = self._detected(frame, regions)
        people = PeopleFrame(heads=det.heads) if det.heads is not None else None
        if self.people is not None:
            background = det.motion.background
            if background is None and self._wants_background:
                # a Motion made without it (by hand, in order with this call): the detector
                # still holds this frame's model
                background = self.detector.background()
            regions, people = self.people.process(frame.image, background, mask, regions,
                                                  self._prev_tracks, work=small)
        owned = self.bridge.measurements(self.tracker.views(), frame.image) if self.bridge else None
        hyps = located = None
        if people is not None:
            # the shape tracker's box of a person the motion detector lost is a hypothesis for
            # that one (lost) track only; it never starts a track (thesis §4.5)
            if self.cfg.people.hypotheses and people.hypotheses_by_track:
                hyps = {tid: r.box.as_array() for tid, r in people.hypotheses_by_track.items()}
            # fitted outlines of tracked people: where each one is inside a merged region
            located = people.located_by_track or None
        moved = getattr(self.tracker, "camera_moved", None)   # the motion-blob tracker's
        if det.motion.step is not None and moved is not None:
            # processing pixels → original: the same rotation and scale, the shift 1/scale
            step = det.motion.step.copy()
            step[:, 2] /= self.scale
            moved(step)
        image, scale = small, self.scale
        if small is None and self.detector is None and self.tracker_sees_pictures:
            # external detections: the detection tracker's appearance reads the frame itself (an
            # empty image is a source of detections alone, without pictures)
            image, scale = (frame.image if frame.image.size else None), 1.0
        tracks = self.tracker.update(regions, dt=self._frame_gap(frame), owned=owned,
                                     image=image, mask=mask, scale=scale, located=located,
                                     frame=frame.index, hypotheses=hyps)
        if self.bridge is not None:
            self.bridge.remember(frame.image, tracks)
        earlier = tuple(self.tracker.confirmed_earlier)
        if self.classes is not None:
            # the tentative frames of the tracks confirmed now vote first
            self.classes.confirm(earlier, frame.index)
            # HOG looks at the processing-scale frame, or the frame itself without the motion
            # stage (none in a source of detections alone)
            if small is None:
                image, scale = (frame.image if frame.image.size else None), 1.0
            tracks = self.classes.update(tracks, dets, self.cfg.detector.match_iou,
                                         self.cfg.detector.vote, image=image, scale=scale)
            earlier = tuple((f, replace(t, label=n, label_score=s))
                            for f, t in earlier for n, s in [self.classes.label(t.id)])
        if not self._report_earlier:
            earlier = ()
        self._prev_tracks = tuple(tracks)
        if self._scene_kind is not None:
            self._vehicles = self._scene_kind.update(tracks)
            self.tracker.vehicles = bool(self._vehicles)
        self.frames_seen += 1
        if mask is not None and self.cfg.regions.silhouettes:
            # what is reported is the regions' silhouettes (the tracker had the mask itself),
            # closed while the scene's tracks are mostly vehicles
            mask = silhouettes(mask, self._speck, close=bool(self._vehicles))
        return FrameResult(index=frame.index, timestamp=frame.timestamp, frame=frame.image,
                           mask=mask, regions=tuple(regions), tracks=tuple(tracks),
                           raw_mask=det.motion.raw_mask, people=people,
                           earlier=earlier,
                           static=det.motion.static if self.report_static else None,
                           discontinuity=frame.discontinuity)

    def _detected(self, frame: Frame, regions: list[Region]) -> tuple[list[Region], Any]:
        """The user's detector on this frame (every ``detector.every`` frames): the regions as
        ``detector.mode`` makes them, and the detections (None in a frame it skips)."""
        d = self.cfg.detector
        if self.frames_seen % d.every:
            return ([] if d.mode == "replace" else regions), None
        dets = self.onnx.detect(frame.image)
        return detector_regions(regions, dets, d.mode, d.start_tracks, d.match_iou), dets

    def process(self, frame: Frame) -> FrameResult:
        """Both stages of one frame."""
        return self.track(frame, self.detect(frame, self.frames_seen))

    def results(self, frames: Iterable[Frame]) -> Iterator[FrameResult]:
        """:meth:`process` over ``frames``. A :class:`Source` that decodes ahead in a thread
        also preprocesses there (:meth:`prepare`). When detection does not depend on the tracks
        (no selective update), the rest of the image work of the next frame (:meth:`motion`:
        the motion detector) runs in a worker thread while this thread finds the current
        frame's regions and tracks them: OpenCV releases the GIL, so the three overlap on two
        cores (benchmarks/throughput.py; docs/benchmarks.md). A detector fed by the tracks and
        the ghost filter (``relearns``: ``vibe``) runs a frame ahead in the same way, fed from
        the state before the current frame (:meth:`_results_fed`); the other detectors with a
        ``protect`` mask run in this thread, with the mask of the previous frame's tracks."""
        prepared = (frames.prepared(self.prepare) if isinstance(frames, Source)
                    else ((f, self.prepare(f)) for f in frames))
        try:
            if self.detector is not None and self.detector.relearns and not self.sequential:
                yield from self._results_fed(prepared)
                return
            if self.sequential or (self.detector is not None and self.detector.protect):
                for frame, small in prepared:
                    yield self.track(frame, self.detect(frame, self.frames_seen, small))
                return
            if self._wants_background and not self.keep_stopped:
                # the shapes make this thread the longest: the worker finds the regions too
                # (they need only the mask and the ghost filter's own state)
                found = prefetch((f, self.regions_of(k, self.motion(f, small)))
                                 for k, (f, small) in enumerate(prepared))
                try:
                    for frame, det in found:
                        yield self.track(frame, det)
                finally:
                    found.close()
                return
            # the worker does the image work; regions and head splitting (Python, holding the
            # GIL) run here, so the worker's OpenCV calls do not wait for the GIL behind them
            # (measured about 5% faster than detecting regions in the worker)
            detected = prefetch((f, self.motion(f, small)) for f, small in prepared)
            try:
                for k, (frame, motion) in enumerate(detected):
                    yield self.track(frame, self.regions_of(k, motion))
            finally:
                detected.close()
        finally:
            # stops the source's reading thread now, also when a stage raised: left to the
            # garbage collector it can still be running when the interpreter exits (abort)
            close = getattr(prepared, "close", None)
            if close is not None:
                close()


    def _results_fed(self, prepared: Iterator) -> Iterator[FrameResult]:
        """:meth:`results` for a detector fed by the tracks (selective update, re-learning):
        the detector works on frame *t* + 1 in a worker thread while this thread finds frame
        *t*'s regions and tracks them, so its ``protect`` mask comes from the tracks of frame
        *t* − 1 (:meth:`feedback`, made here before the worker starts; the same in every run)."""
        self.sequential_feedback = False
        prepared = iter(prepared)
        pool = ThreadPoolExecutor(1, thread_name_prefix="motiontrack-motion")
        try:
            item = next(prepared, None)
            if item is None:
                return
            job = pool.submit(self.motion, item[0], item[1], self.feedback(*item))
            for k in itertools.count():
                frame = item[0]
                motion = job.result()
                try:
                    item = next(prepared, None)
                except Exception:
                    # the source failed (a camera that does not come back): the frame already
                    # detected is still tracked and handed on before the error
                    yield self.track(frame, self.regions_of(k, motion))
                    raise
                if item is not None:
                    job = pool.submit(self.motion, item[0], item[1], self.feedback(*item))
                yield self.track(frame, self.regions_of(k, motion))
                if item is None:
                    return
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
            self.sequential_feedback = True


class TrackRun:
    """The frames of one source through a :class:`Pipeline`: an iterator of
    :class:`FrameResult` that owns the source and the pipeline's threads.

    Use it as a context manager or call :meth:`close` when done early; a run left open is closed
    when it is garbage-collected or, at the latest, when the interpreter exits, so the decoding
    and detection threads never outlive it.
    """

    def __init__(self, source: Any, config: PipelineConfig | str | Path | None = None,
                 detections: Annotations | None = None) -> None:
        cfg = resolve_config(config)
        self.source = open_configured_source(source, cfg.source)
        try:
            info = self.source.info
            self.pipeline = Pipeline(cfg, (info.width, info.height), detections, info.fps,
                                     camera=fitted_camera(cfg, info.width, info.height))
        except BaseException:
            self.source.close()
            raise
        self._results = self.pipeline.results(self.source)
        _OPEN_RUNS.add(self)

    def __iter__(self) -> "TrackRun":
        return self

    def __next__(self) -> FrameResult:
        return next(self._results)

    def close(self) -> None:
        """Stop the threads and close the source (safe to call more than once)."""
        _OPEN_RUNS.discard(self)
        try:
            self._results.close()
        finally:
            self.source.close()

    def __enter__(self) -> "TrackRun":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


#: runs not closed yet: closed at interpreter exit, while their threads can still be joined
_OPEN_RUNS: "weakref.WeakSet[TrackRun]" = weakref.WeakSet()


@atexit.register
def _close_open_runs() -> None:
    for r in list(_OPEN_RUNS):
        r.close()


def fitted_camera(cfg: PipelineConfig, width: int, height: int) -> Any:
    """``measure.camera`` fitted to frames of ``width`` x ``height`` when the track classifier
    measures with it (``classes.enabled``), else None."""
    if not (cfg.measure.camera and cfg.classes.enabled):
        return None
    from .calibrate import fit_to_image, load_camera   # with a camera only

    return fit_to_image(load_camera(cfg.measure.camera), width, height, cfg.measure.camera)


def run(source: Any, config: PipelineConfig | str | Path | None = None,
        detections: Annotations | None = None) -> TrackRun:
    """A :class:`TrackRun` over every frame of ``source`` (see :func:`open_source`)."""
    return TrackRun(source, config, detections)


def open_configured_source(source: Any, sc: SourceConfig) -> Source:
    """Open ``source`` with the start/length, frame rate (``source.fps``) and live-reconnection
    settings ``sc`` (``PipelineConfig.source``); a :class:`Source` is returned as it is. Frames
    far larger than the defaults are sized for get a warning with the memory to expect; frames
    of more than ``source.max_pixels`` are refused."""
    if isinstance(source, Source):
        return source
    src = open_source(source, sc.start, sc.max_frames, max_pixels=sc.max_pixels,
                      reconnect_attempts=sc.reconnect_attempts,
                      backoff=sc.reconnect_backoff, backoff_max=sc.reconnect_backoff_max,
                      reset_frames=sc.reconnect_reset_frames, read_timeout=sc.read_timeout_s)
    if src.info.width * src.info.height > sc.max_pixels:   # any other source, once opened
        src.close()
        raise too_many_pixels(src.info.name, src.info.width, src.info.height, sc.max_pixels)
    if sc.fps > 0:
        src.set_fps(sc.fps)
    warn_if_oversized(src.info.width, src.info.height, src.info.name)
    return src
