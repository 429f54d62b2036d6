"""The pipeline: the only module that knows the stage order.

    source → preprocess → motion (mask) → clean-up → regions → tracker → FrameResult

:func:`run` yields one :class:`~motiontrack.types.FrameResult` per frame (the Python API).
:class:`TrackJob` drives :func:`run` and writes the outputs of ``motiontrack track`` (annotated
video, mask video, ``tracks.txt``, ``summary.json``, resolved ``config.toml``); it finalises every
output with what was processed so far when the run is interrupted.
"""

from __future__ import annotations

import json
import logging
import statistics
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

import numpy as np

from .annotate import annotate_frame
from .config import PipelineConfig, load_config, save_config
from .errors import RunOutcome
from .intermediate import IntermediateWriter, parse_streams
from .io.atomic import atomic_open, atomic_write_text, check_writable
from .io.mot import format_mot_rows, read_mot, write_mot
from .io.sources import Source, open_source, prefetch
from .io.video import VideoSink, extension_for
from .motion import create_detector
from .motion.cleanup import clean_mask
from .preprocess import load_roi, pixel_window, preprocess, resolve_scale, scaled_size
from .regions import find_regions
from .tracking.tracker import TRACKERS
from .types import Annotations, Box, Frame, FrameResult, Region, Track

log = logging.getLogger(__name__)

__all__ = ["Pipeline", "run", "TrackJob", "JobSummary", "resolve_config", "completes_tracks",
           "fill_gap_frames", "reported"]


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


def completes_tracks(cfg: PipelineConfig, external: bool) -> bool:
    """Whether a run's tracks get their tentative frames (``tracker.backfill``) and their gaps
    filled (``tracker.fill_gaps_s``): tracks from external detections, or from motion regions with
    ``tracker.fill_motion``."""
    return external or cfg.tracker.fill_motion


def fill_gap_frames(cfg: PipelineConfig, fps: float | None, external: bool) -> int:
    """Longest gap (frames) of a track that :class:`TrackJob` fills by interpolation in
    ``tracks.txt`` (0 = none): ``tracker.fill_gaps_s`` at the source's frame rate (25 fps when
    unknown), when :func:`completes_tracks`. See :func:`motiontrack.tracking.gaps.fill_gaps`."""
    if not completes_tracks(cfg, external):
        return 0
    return int(round(cfg.tracker.fill_gaps_s * (fps or 25.0)))


def reported(res: FrameResult) -> list[tuple[int, Track]]:
    """``(frame index, track)`` rows one frame adds to the tracks file: its tracks, then the
    tracks confirmed in it at their earlier, tentative frames (:attr:`FrameResult.earlier`)."""
    return [*((res.index, t) for t in res.tracks), *res.earlier]


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
    """

    def __init__(self, cfg: PipelineConfig, image_size: tuple[int, int],
                 detections: Annotations | None = None, fps: float | None = None) -> None:
        self.cfg = cfg
        self._min_gap: float | None = None   # shortest time between frames seen: one period
        self._last_ts: float | None = None
        self.image_size = image_size
        self.scale = resolve_scale(cfg.preprocess.scale, *image_size)
        self.detections = detections
        self._det_index = detections.by_frame() if detections is not None else None
        self.detector = create_detector(cfg.motion) if detections is None else None
        pre = cfg.preprocess
        if self.detector is not None and self.detector.wants_color and pre.grayscale:
            pre = replace(pre, grayscale=False)
        self.pre_cfg = replace(pre, scale=self.scale)  # the resolved (automatic) scale
        pw, ph = scaled_size(image_size[0], image_size[1], self.scale)
        self.roi = load_roi(pre.roi, pw, ph) if pre.roi else None
        tracker_cfg = cfg.tracker
        if detections is not None:
            # a detector's box is one object: there is no merged blob to split (split shares of a
            # box that overlaps a neighbour's prediction swap identities; benchmarks/detections.py),
            # and no fragment at an occluder's edge to tilt the Kalman velocity (coasting at the
            # median pace there: HOTA the same in sum over the benchmark's rows, MOTA -0.028
            # with 20% dropped boxes)
            tracker_cfg = replace(tracker_cfg, split_merged=False, coast_frames=0)
        self.tracker = TRACKERS.get(cfg.tracker.method)(tracker_cfg, image_size, fps)
        # a confirmed track's tentative frames (FrameResult.earlier)
        self.tracker.keep_tentative = (cfg.tracker.backfill
                                       and completes_tracks(cfg, detections is not None))
        self.people = None
        if cfg.people.enabled:
            from .people import PeopleStage

            self.people = PeopleStage(cfg.people)
        #: head detector settings for ``people.auto_split`` (None = off): merged regions are split
        #: between heads, with the people stage off, while the scene's regions are upright
        self.auto_heads: dict[str, float] | None = None
        if (not cfg.people.enabled and cfg.people.auto_split and cfg.people.heads
                and cfg.people.split and self.detector is not None):
            from .people import head_params

            self.auto_heads = head_params(cfg.people)
        self._upright: float | None = None   # running mean of the frames' median region h/w
        self.ghosts = None
        if cfg.motion.ghost_ratio > 0 and self.detector is not None:
            from .motion.ghosts import GhostFilter

            self.ghosts = GhostFilter(cfg.motion.ghost_ratio, pixels=cfg.motion.ghost_pixels)
        self._prev_tracks: tuple = ()
        self.bridge = None
        if cfg.tracker.bridge != "none":
            from .tracking.bridge import Bridge

            self.bridge = Bridge(cfg.tracker.bridge, cfg.tracker.bridge_frames)
        self.frames_seen = 0
        #: run detection and tracking in one thread (needed when a later stage reads the
        #: detector's state, e.g. its background image, for the same frame). Head-based
        #: splitting needs only the mask: it runs in this thread while the worker detects the
        #: next frame (measured faster than running it in the worker, which it would slow down).
        self.sequential = self.people is not None and self.people.needs_tracks

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

    def _protect_mask(self, shape: tuple[int, int]) -> np.ndarray | None:
        """Pixels (processing scale) where moving tracks are expected: not learnt as background."""
        if not self.detector.protect:
            return None
        boxes = self.tracker.moving_boxes()
        if not len(boxes):
            return None
        mask = np.zeros(shape, bool)
        for box in boxes:
            x1, y1, x2, y2 = pixel_window(box, self.scale, shape)
            if x2 > x1 and y2 > y1:
                mask[y1:y2, x1:x2] = True
        return mask

    def detect(self, frame: Frame, index: int, small: np.ndarray | None = None
               ) -> tuple[np.ndarray | None, list[Region], dict[str, Any]]:
        """Motion stage of one frame: ``(mask, regions, extras)``. ``index`` counts frames from
        the start of this run (for the warm-up); ``small`` is :meth:`prepare`'s image of the
        frame when already made."""
        return self.regions_of(index, *self.motion(frame, small))

    def prepare(self, frame: Frame) -> np.ndarray | None:
        """The frame at processing scale, preprocessed (None with external detections): the
        part of the image work that needs nothing but the frame, so a source that decodes
        ahead can do it in its thread (:meth:`~motiontrack.io.sources.Source.prepared`)."""
        return preprocess(frame.image, self.pre_cfg) if self.detector is not None else None

    def motion(self, frame: Frame, small: np.ndarray | None = None
               ) -> tuple[np.ndarray | None, dict[str, Any]]:
        """First half of :meth:`detect`, the image work (OpenCV, which releases the GIL):
        ``(mask, extras)``; with external detections ``(None, {"detections": regions})``."""
        if self._det_index is not None:
            return None, {"detections": _regions_from_detections(
                self.detections, self._det_index.get(frame.index + 1))}
        if small is None:
            small = self.prepare(frame)
        raw = self.detector.apply(small, self._protect_mask(small.shape[:2]))
        if self.roi is not None:
            raw = np.bitwise_and(raw, self.roi)
        return clean_mask(raw, self.cfg.cleanup), {"raw_mask": raw, "small": small}

    def regions_of(self, index: int, mask: np.ndarray | None, extras: dict[str, Any]
                   ) -> tuple[np.ndarray | None, list[Region], dict[str, Any]]:
        """Second half of :meth:`detect`: the mask's regions, split between heads while the
        scene is upright (``people.auto_split``)."""
        if mask is None:
            return None, extras["detections"], {}
        if self.ghosts is not None:   # it learns its background in the warm-up frames too
            mask, regions = self.ghosts.regions(extras["small"], mask, self._find, self.scale)
        else:
            regions = self._find(mask)
        if index < self.cfg.motion.warmup:
            regions = []
        if regions:
            regions = self._split_upright(mask, regions, extras)
        return mask, regions, extras

    def _find(self, mask: np.ndarray) -> list[Region]:
        return find_regions(mask, self.cfg.regions, self.scale, self.image_size)

    def _split_upright(self, mask: np.ndarray, regions: list[Region], extras: dict[str, Any]
                       ) -> list[Region]:
        """``people.auto_split``: while the scene's regions are upright (a running mean of each
        frame's median height/width at least ``people.upright_ratio``: people, not cars), split
        every region clearly wider than that typical shape between the heads found in it."""
        if self.auto_heads is None:
            return regions
        ratio = self.cfg.people.upright_ratio
        shapes = [r.box.h / r.box.w for r in regions]
        shape = float(statistics.median(shapes))   # a tenth of np.median's cost on a short list
        self._upright = (shape if self._upright is None
                         else (1 - _SCENE_RATE) * self._upright + _SCENE_RATE * shape)
        if self._upright < ratio:
            return regions
        # searched for heads: regions a third wider than the scene's typical one (a lone person
        # is left alone; two people side by side are twice as wide)
        wide = [s < _WIDE * self._upright for s in shapes]
        if not any(wide):
            return regions
        from .people.heads import split_regions_by_heads

        regions, extras["heads"] = split_regions_by_heads(
            mask, regions, mask.shape[1] / self.image_size[0], search=wide, **self.auto_heads)
        return regions

    def track(self, frame: Frame, mask: np.ndarray | None, regions: list[Region],
              extras: dict[str, Any]) -> FrameResult:
        """Tracking stage of one frame, after :meth:`detect` (and the people stage, when on)."""
        if self.people is not None:
            background = self.detector.background() if self.detector is not None else None
            regions, people_extras = self.people.process(
                frame.image, background, mask, regions, self._prev_tracks, work=extras.get("small"))
            extras = {**extras, **people_extras}
        owned = self.bridge.measurements(self.tracker, frame.image) if self.bridge else None
        hyps = extras.get("hypotheses_by_track") if self.cfg.people.hypotheses else None
        outlines = extras.get("located_by_track")
        located = None
        if hyps or outlines:
            meta = self.tracker.meta
            index = {m.tid: i for i, m in enumerate(meta) if m.tid > 0}  # public id -> track index
        if hyps:
            # the shape tracker's box of a person the motion detector lost is a hypothesis for
            # that one (lost) track only; it never starts a track (thesis §4.5)
            owned = dict(owned or {})
            for tid, region in hyps.items():
                i = index.get(tid)
                if i is not None and meta[i].tsu > 0 and i not in owned:
                    owned[i] = region.box.as_array()
        if outlines:
            # fitted outlines of tracked people: where each one is inside a merged region
            located = {index[tid]: box for tid, box in outlines.items() if tid in index}
        tracks = self.tracker.update(regions, dt=self._frame_gap(frame), owned=owned,
                                     image=extras.get("small"), mask=mask, scale=self.scale,
                                     located=located, frame=frame.index)
        if self.bridge is not None:
            self.bridge.remember(frame.image, tracks)
        self._prev_tracks = tuple(tracks)
        self.frames_seen += 1
        return FrameResult(index=frame.index, timestamp=frame.timestamp, frame=frame.image,
                           mask=mask, regions=tuple(regions), tracks=tuple(tracks), extras=extras,
                           earlier=tuple(self.tracker.confirmed_earlier))

    def process(self, frame: Frame) -> FrameResult:
        """Both stages of one frame."""
        return self.track(frame, *self.detect(frame, self.frames_seen))

    def results(self, frames: Iterable[Frame]) -> Iterator[FrameResult]:
        """:meth:`process` over ``frames``. A :class:`Source` that decodes ahead in a thread
        also preprocesses there (:meth:`prepare`). When detection does not depend on the tracks
        (no selective update), the rest of the image work of the next frame (:meth:`motion`:
        the motion detector) runs in a worker thread while this thread finds the current
        frame's regions and tracks them: OpenCV releases the GIL, so the three overlap on two
        cores (benchmarks/throughput.py; docs/benchmarks.md)."""
        prepared = (frames.prepared(self.prepare) if isinstance(frames, Source)
                    else ((f, self.prepare(f)) for f in frames))
        try:
            if self.sequential or (self.detector is not None and self.detector.protect):
                for frame, small in prepared:
                    yield self.track(frame, *self.detect(frame, self.frames_seen, small))
                return
            # the worker does the image work; regions and head splitting (Python, holding the
            # GIL) run here, so the worker's OpenCV calls do not wait for the GIL behind them
            # (measured about 5% faster than detecting regions in the worker)
            detected = prefetch((f, self.motion(f, small)) for f, small in prepared)
            try:
                for k, (frame, (mask, extras)) in enumerate(detected):
                    yield self.track(frame, *self.regions_of(k, mask, extras))
            finally:
                detected.close()
        finally:
            # stops the source's reading thread now, also when a stage raised: left to the
            # garbage collector it can still be running when the interpreter exits (abort)
            close = getattr(prepared, "close", None)
            if close is not None:
                close()


def run(source: Any, config: PipelineConfig | str | Path | None = None,
        detections: Annotations | None = None) -> Iterator[FrameResult]:
    """Yield a :class:`FrameResult` for every frame of ``source`` (see :func:`open_source`)."""
    cfg = resolve_config(config)
    src = open_configured_source(source, cfg)
    pipe = Pipeline(cfg, (src.info.width, src.info.height), detections, src.info.fps)
    try:
        yield from pipe.results(src)
    finally:
        src.close()


def open_configured_source(source: Any, cfg: PipelineConfig) -> Source:
    """Open ``source`` with the start/length and live-reconnection settings of ``cfg``."""
    if isinstance(source, Source):
        return source
    sc = cfg.source
    return open_source(source, sc.start, sc.max_frames, reconnect_attempts=sc.reconnect_attempts,
                       backoff=sc.reconnect_backoff, backoff_max=sc.reconnect_backoff_max)


# ------------------------------------------------------------------------------------ the job
@dataclass
class JobSummary:
    """What ``summary.json`` holds."""

    source: str
    width: int
    height: int
    source_fps: float | None
    frames: int = 0
    seconds: float = 0.0
    tracks: int = 0
    status: str = "complete"
    interrupted: bool = False
    truncated: bool = False
    outputs: dict[str, str] = field(default_factory=dict)
    accuracy: dict[str, float] | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def fps(self) -> float:
        return self.frames / self.seconds if self.seconds > 0 else 0.0

    def as_dict(self) -> dict[str, Any]:
        d = {
            "source": self.source, "width": self.width, "height": self.height,
            "source_fps": self.source_fps, "frames": self.frames,
            "seconds": round(self.seconds, 3), "fps": round(self.fps, 2), "tracks": self.tracks,
            "status": self.status, "interrupted": self.interrupted, "truncated": self.truncated,
            "outputs": self.outputs,
        }
        if self.accuracy is not None:
            d["accuracy"] = self.accuracy
        d.update(self.extra)
        return d


class TrackJob:
    """``motiontrack track``: run the pipeline on a source and write every output to ``out_dir``.

    Outputs are streamed to temporary files and renamed into place when the job ends, whether it
    finishes, the source fails mid-way, or the user interrupts (then ``summary.json`` says
    ``"interrupted": true``).
    """

    def __init__(self, source: Any, cfg: PipelineConfig, out_dir: str | Path, *, force: bool = False,
                 gt: Annotations | None = None, detections: Annotations | None = None,
                 show: Callable[[np.ndarray], bool] | None = None, save: Iterable[str] = ()) -> None:
        self.cfg = cfg
        self.out = Path(out_dir)
        self.src = open_configured_source(source, cfg)
        self.gt = gt
        if self.gt is None and hasattr(self.src, "ground_truth"):
            self.gt = self.src.ground_truth()
        self.detections = detections
        self.show = show
        self.paths = {
            "tracks": self.out / "tracks.txt",
            "summary": self.out / "summary.json",
            "config": self.out / "config.toml",
        }
        if cfg.output.video:
            self.paths["video"] = self.out / f"annotated{extension_for(cfg.output.codec)}"
        if cfg.output.mask_video:
            self.paths["mask_video"] = self.out / f"mask{extension_for(cfg.output.codec)}"
        if self.gt is not None:
            self.paths["gt"] = self.out / "gt.txt"
        self.save = parse_streams(save)
        self.backfilled = 0   # rows written at a track's tentative frames (FrameResult.earlier)
        for stream in self.save:
            self.paths[stream] = self.out / f"{stream}{extension_for(cfg.output.codec)}"
        check_writable(list(self.paths.values()), force)
        self.camera = None
        if cfg.measure.camera:
            from .calibrate import load_camera

            self.camera = load_camera(cfg.measure.camera)
        # build every stage now: a bad plug-in name or ROI fails before anything is written
        self.pipe = Pipeline(cfg, (self.src.info.width, self.src.info.height), detections,
                             self.src.info.fps)
        # saving the background reads the detector's model after each frame, as the people
        # stage's shapes and HOG do: detection of the next frame must not run meanwhile
        self.pipe.sequential = self.pipe.sequential or "background" in self.save

    def expected_frames(self) -> int | None:
        return self.src.expected_frames()

    def run(self, progress: Callable[[int], None] | None = None,
            should_stop: Callable[[], bool] | None = None) -> JobSummary:
        """Process the source and write the outputs.

        ``should_stop`` is polled after each complete frame (the CLI's signal handlers set it), so
        an interruption never splits a frame between the outputs. A ``KeyboardInterrupt`` raised
        mid-frame is handled too. Either way the outputs are finalised, ``summary.json`` records
        ``"interrupted": true``, and ``KeyboardInterrupt`` is re-raised. A live source that fails
        for good (:class:`SourceError`) is handled the same way and its error re-raised.
        """
        cfg, info = self.cfg, self.src.info
        self.out.mkdir(parents=True, exist_ok=True)
        save_config(cfg, self.paths["config"])
        fps = info.fps or 25.0
        summary = JobSummary(source=info.name, width=info.width, height=info.height, source_fps=info.fps)
        if self.detections is None:
            # the scale detection ran at (``preprocess.scale = 0`` is resolved per frame size)
            summary.extra["processing_scale"] = round(self.pipe.scale, 4)
            log.info("processing at scale %.3g (%dx%d)", self.pipe.scale,
                     *scaled_size(info.width, info.height, self.pipe.scale))
        video = VideoSink(self.paths["video"], fps, cfg.output.codec) if "video" in self.paths else None
        mask_video = (VideoSink(self.paths["mask_video"], fps, cfg.output.codec)
                      if "mask_video" in self.paths else None)
        inter = IntermediateWriter(self.out, self.save, fps, cfg.output.codec) if self.save else None
        ids: set[int] = set()
        t0 = time.perf_counter()
        pipe = self.pipe

        with atomic_open(self.paths["tracks"]) as tracks_fh:
            try:
                with RunOutcome() as outcome:
                    for res in pipe.results(self.src):
                        if not self._write_frame(res, tracks_fh, video, mask_video, inter, ids):
                            summary.status = "stopped by user"
                            break
                        summary.frames += 1
                        if progress is not None:
                            progress(1)
                        if should_stop is not None and should_stop():
                            raise KeyboardInterrupt
            finally:
                summary.seconds = time.perf_counter() - t0
                for sink in (video, mask_video, inter):
                    if sink is not None:
                        sink.close()
        if outcome.status != "complete":
            log.warning("%s after %d frames; writing what was processed", outcome.status,
                        summary.frames)
            summary.status = outcome.status
        summary.interrupted = outcome.interrupted
        summary.truncated = summary.truncated or self.src.truncated or outcome.failed
        summary.tracks = len(ids)
        summary.outputs = {k: str(v) for k, v in self.paths.items()
                           if v.exists() or k == "summary"}
        complete = completes_tracks(cfg, self.detections is not None)
        if complete or self.camera is not None or self.gt is not None:
            # read the run back from its tracks file: nothing accumulates in memory per frame
            pred = read_mot(self.paths["tracks"], kind="results")
            if complete:
                pred = self._complete_tracks(pred, summary)
            if self.camera is not None:
                from .calibrate import track_measurements

                summary.extra["measurements"] = {
                    str(k): v for k, v in track_measurements(pred.frames, pred.ids, pred.boxes,
                                                             self.camera, fps).items()}
            if self.gt is not None:
                summary.accuracy = score_run(self.gt, pred, summary.frames, self.src)
                write_mot(self.gt, self.paths["gt"], kind="gt")
                summary.outputs["gt"] = str(self.paths["gt"])
        atomic_write_text(self.paths["summary"], json.dumps(summary.as_dict(), indent=2) + "\n")
        outcome.reraise()  # everything is written; an interrupt or a failed source still surfaces
        return summary

    def _complete_tracks(self, pred: Annotations, summary: JobSummary) -> Annotations:
        """Rewrite ``tracks.txt`` (atomically) sorted by frame, then id, with each track's short
        gaps filled by interpolation (:func:`fill_gap_frames`); the filled rows get their world
        position from the camera. The tentative frames (:attr:`backfilled`) are in it already."""
        from .tracking.gaps import fill_gaps

        max_gap = fill_gap_frames(self.cfg, self.src.info.fps, self.detections is not None)
        filled = fill_gaps(pred, max_gap)
        summary.extra["backfilled_rows"] = self.backfilled
        summary.extra["filled_rows"] = len(filled) - len(pred)
        if self.camera is not None:
            new = (filled.world == -1.0).all(axis=1)
            filled.world[new] = self._world(filled.boxes[new])
        write_mot(filled, self.paths["tracks"], kind="results")   # sorted by frame, then id
        log.info("tracks.txt: %d rows at tentative frames, %d filled in gaps of up to %d frames",
                 self.backfilled, len(filled) - len(pred), max_gap)
        return filled

    def _world(self, boxes: np.ndarray) -> np.ndarray:
        """Ground-plane positions ``(x, y, 0)`` in metres of the boxes' foot points."""
        from .calibrate import world_positions

        return np.column_stack([world_positions(boxes, self.camera), np.zeros(len(boxes))])

    def _write_frame(self, res: FrameResult, tracks_fh, video: VideoSink | None,
                     mask_video: VideoSink | None, inter: IntermediateWriter | None,
                     ids: set[int]) -> bool:
        """Append one frame to every output; False when the live viewer asked to stop."""
        cfg = self.cfg
        # tracks confirmed now are also written at their tentative frames: out of frame order
        # until the file is rewritten sorted when the run ends
        rows = reported(res)
        self.backfilled += len(res.earlier)
        if rows:
            boxes = np.array([t.box.as_array() for _, t in rows])
            tid = [t.id for _, t in rows]
            world = self._world(boxes) if self.camera is not None else None
            tracks_fh.write(format_mot_rows([f + 1 for f, _ in rows], tid, boxes,
                                            [t.score for _, t in rows], world))
            ids.update(tid)
        if video is not None or self.show is not None:
            img = annotate_frame(res.frame, res.tracks, res.regions, res.mask, cfg.output.trail,
                                 cfg.output.mask_inset, text=f"frame {res.index}")
            if self.pipe.people is not None:
                from .people.draw import draw_people

                draw_people(img, res.extras, inplace=True)
            if video is not None:
                video.write(img)
            if self.show is not None and not self.show(img):
                return False
        if mask_video is not None and res.mask is not None:
            mask_video.write(res.mask)
        if inter is not None:
            inter.write(res, self.pipe.detector)
        return True


def score_run(gt: Annotations, pred: Annotations, frames: int, src: Source) -> dict[str, float]:
    """Accuracy of a run against ground truth restricted to the processed frames."""
    from .evaluate.mot import evaluate_tracking

    start = getattr(src, "start", 0)
    lo, hi = start + 1, start + frames
    gt = gt.select((gt.frames >= lo) & (gt.frames <= hi))
    # rows with consider = 0 (occluded synthetic people, PETS people outside the area) are
    # ignore regions: a box on them is neither a hit nor a false positive
    res = evaluate_tracking(gt, pred, ignore_zero_marked=True)
    keys = ("HOTA", "MOTA", "IDF1", "MOTP", "DetA", "AssA", "IDSW", "TP", "FP", "FN")
    out = {k: float(res[k]) for k in keys if k in res}
    out["recall"] = float(res.get("recall", 0.0))   # CLEAR's CLR_Re and CLR_Pr
    out["precision"] = float(res.get("precision", 0.0))
    return out
