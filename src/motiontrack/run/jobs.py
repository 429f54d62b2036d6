"""The jobs of the commands: which processor and which writers each one runs.

``track_job`` is ``motiontrack track``; ``follow_job``, ``sparse_flow_job`` and
``dense_flow_job`` are ``follow`` and ``flow``. Sweeps and tuning compose their own writers
(:func:`motiontrack.studies.sweep.execute_run`).
"""

from __future__ import annotations

import functools
import logging
import os
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterable, Sequence

from ..config import PipelineConfig, SourceConfig, save_config
from ..errors import ConfigError
from ..evaluate.scoring import DEFAULT_SCORING, ignores_zero_marked
from ..io.atomic import is_stdout
from ..io.pacing import PacedSource
from ..io.sources import Source
from ..imaging import scaled_size
from ..io.video import extension_for
from ..pipeline import completes_tracks, fill_gap_frames, open_configured_source
from ..render.streams import parse_streams
from ..types import Annotations, Box
from .folder import RunFolder
from .folders import source_name
from .job import Job, Writer
from .processors import (DenseFlowProcessor, FollowProcessor, OverlayProcessor,
                         SparseFlowProcessor, TrackProcessor)
from .writers import (IntermediateWriter, MaskImagesWriter, MaskVideoWriter, ScoreWriter,
                      StillsWriter, TracksWriter, VideoWriter, ViewerWriter)

if TYPE_CHECKING:
    # a job imports what only some runs use when the run asks for it: a scene (analytics), a
    # camera (calibrate), ground truth (the metrics), event sinks, another command's tracker
    import numpy as np

    from ..tracking.flow import SparseFlowParams
    from ..tracking.single import SingleTracker

log = logging.getLogger(__name__)

__all__ = ["track_job", "follow_job", "sparse_flow_job", "dense_flow_job", "overlay_job"]


def _opened(source: Any, sc: SourceConfig, build: Callable[[Source], Job]) -> Job:
    """``build(source)`` with the source opened by the settings ``sc``, closed again when
    building fails."""
    src = open_configured_source(source, sc)
    try:
        return build(src)
    except BaseException:
        src.close()
        raise


def track_job(source: Any, cfg: PipelineConfig, out_dir: str | Path, *, force: bool = False,
              gt: Annotations | None = None, detections: Annotations | None = None,
              show: Callable[[np.ndarray], bool] | None = None,
              save: Iterable[str] | str = (), mask_images: str | Path | None = None,
              scoring: str = DEFAULT_SCORING,
              scene: str | Path | Callable[[Any], Any] | None = None,
              bin_s: float = 60.0, sinks: Sequence[Any] = (),
              camera_name: str | None = None, sink_settings: Any = None,
              writers: Sequence[Writer] = (), pace: bool = False, by_class: bool = False,
              store_events: bool = True) -> Job:
    """``motiontrack track``: ``tracks.txt``, the annotated video, the mask video and the
    intermediate movies as ``cfg.output`` and ``save`` ask, the mask of every frame as
    ``bin%06d.png`` in the folder ``mask_images``, the live view with ``show``, ``gt.txt`` and
    the accuracy with ground truth (given, or the source's own), ``summary.json`` and
    ``config.toml``. ``scoring`` names how zero-marked ground truth counts
    (:data:`~motiontrack.evaluate.scoring.SCORING`). A ``scene`` file runs scene analytics on
    the tracks of each frame: ``events.jsonl`` and ``counts.csv`` (rows of ``bin_s`` seconds),
    the lines and zones with their counts on the annotated video; ``scene`` may also be a
    function of the camera model fitted to the source (None without one) that returns the
    :class:`~motiontrack.analytics.Scene` to run, or None for none (``serve`` keeps a camera's
    last valid scene this way); ``by_class``: each class's crossings in ``counts.csv``, a heat
    map of each class. ``sinks`` (webhook and MQTT targets, :mod:`motiontrack.io.sinks`)
    receive every event too, named ``camera_name`` (default: the source's name,
    :func:`~motiontrack.run.folders.source_name`), sent as ``sink_settings`` say (a
    :class:`~motiontrack.io.sinks.SinkSettings`). ``writers`` are more outputs, given every
    frame after the others (``serve``'s live view). ``pace`` plays a recorded source at its own
    frame rate (:class:`~motiontrack.io.pacing.PacedSource`: ``track --show``). With a scene and
    ``store_events``, the events are also kept in the run's event store ``events.db`` under
    ``camera_name`` (default: the source's name); ``serve`` keeps them in one store of its own
    instead."""
    out = Path(out_dir)
    ignores_zero_marked(scoring)   # an unknown name fails before the source opens
    store_camera = camera_name or source_name(source)
    camera_name = _sink_camera_name(sinks, scene, camera_name, source)
    if mask_images is not None and detections is not None:
        raise ConfigError("--mask-images needs motion masks; with --detections there are none")
    streams = _streams(cfg, save)
    more = list(writers)
    camera = _load_camera(cfg.measure.camera)

    def build(src: Source) -> Job:
        if pace:
            src = PacedSource(src)
        truth = gt if gt is not None else src.ground_truth()
        external = detections is not None
        fitted = _fitted(camera, src, cfg.measure.camera)
        analytics = _analytics(scene, fitted, src.info.fps) if scene is not None else None
        proc = TrackProcessor(cfg, src.info, detections,
                              needs_background="background" in streams, analytics=analytics,
                              camera=fitted)
        if not external:
            info, scale = src.info, proc.pipe.scale
            log.info("processing at scale %.3g (%dx%d)", scale,
                     *scaled_size(info.width, info.height, scale))
        fill = (fill_gap_frames(cfg, src.info.fps, external) if completes_tracks(cfg, external)
                else None)
        tracks = TracksWriter(out, fitted, fill)
        writers: list[Writer] = [tracks]
        if analytics is not None:
            writers += _scene_writers(out, _source_label(source, src), analytics.scene, fitted,
                                      bin_s, by_class)
            if store_events:
                from .event_store_writer import EventStoreWriter

                writers.append(EventStoreWriter(RunFolder(out).event_store, store_camera,
                                                evidence=out))
        writers += _picture_writers(out, cfg, streams, mask_images, force, show)
        if truth is not None:
            from ..evaluate.score import score_run

            writers.append(ScoreWriter(out, truth, tracks,
                                       functools.partial(score_run, scoring=scoring)))
        if sinks:
            from .event_sinks import sinks_writer

            writers.append(sinks_writer(sinks, camera_name, sink_settings))
        return Job(src, proc, [*writers, *more], out, force=force, config=(save_config, cfg))

    return _opened(source, cfg.source, build)


def _streams(cfg: PipelineConfig, save: Iterable[str] | str) -> tuple[str, ...]:
    """The intermediate movies ``save`` asks for, but the annotated video when it is written
    anyway (the movie would be written to its file name)."""
    streams = parse_streams(save)
    if cfg.output.video and "annotated" in streams:
        log.info("--save annotated: the annotated video is written anyway")
        streams = tuple(s for s in streams if s != "annotated")
    return streams


def _fitted(camera: Any, src: Source, path: str) -> Any:
    """The camera model fitted to the source's frame size (None without one)."""
    if camera is None:
        return None
    from ..calibrate import fit_to_image

    return fit_to_image(camera, src.info.width, src.info.height, path)


def _load_camera(path: str) -> Any:
    """The camera model of ``measure.camera`` (None without one)."""
    if not path:
        return None
    from ..calibrate import load_camera   # with a camera only

    return load_camera(path)


def _analytics(scene: str | Path | Callable[[Any], Any], camera: Any, fps: float | None
               ) -> Any:
    """The scene analytics of ``scene`` (a file, or a function of ``camera`` that returns the
    scene or None) on a source of ``fps`` frames a second; None when there is no scene."""
    from ..analytics import Analytics, load_scene

    sc = scene(camera) if callable(scene) else load_scene(scene, camera)
    return Analytics(sc, fps or 25.0, camera) if sc is not None else None


def _sink_camera_name(sinks: Sequence[Any], scene: Any, camera_name: str | None,
                      source: Any) -> str | None:
    """The camera name events are sent under (checked), or None without sinks."""
    if sinks and scene is None:
        raise ConfigError("--webhook and --mqtt send scene-analytics events: give --scene")
    if not sinks:
        return None
    from ..io.sinks import check_camera_name

    return check_camera_name(camera_name or source_name(source))


def _source_label(source: Any, src: Source) -> str:
    """The source as ``events.jsonl`` names it: as given, or for a Source object (serve's
    segments) the name its summary gives it."""
    return str(source if isinstance(source, (str, int, os.PathLike)) else src.info.name)


def _scene_writers(out: Path, source: str, sc: Any, camera: Any, bin_s: float,
                   by_class: bool = False) -> list[Writer]:
    """``events.jsonl``, ``counts.csv`` and the heat maps of the scene ``sc`` (``by_class``:
    the crossings of each class in ``counts.csv`` and a heat map of each class)."""
    from ..classify import CLASS_NAMES
    from .analytics_writers import CountsWriter, EventsWriter
    from .heatmaps import HeatmapWriter, scene_geometry

    geometry = scene_geometry(sc.lines, sc.zones)
    writers: list[Writer] = [
        EventsWriter(out, source, sc.source),
        CountsWriter(out, sc.lines, sc.zones, bin_s, by_class=by_class),
        HeatmapWriter(out, sc.anchor, camera=camera, geometry=geometry)]
    if by_class:
        writers += [HeatmapWriter(out, sc.anchor, geometry=geometry, label=c)
                    for c in CLASS_NAMES]
    return writers


def _picture_writers(out: Path, cfg: PipelineConfig, streams: Sequence[str],
                     mask_images: str | Path | None, force: bool,
                     show: Callable[[np.ndarray], bool] | None) -> list[Writer]:
    """The annotated video, the mask video, the intermediate movies, the mask images and the
    live view, as ``cfg.output`` and the options ask."""
    codec = cfg.output.codec
    writers: list[Writer] = []
    if cfg.output.video:
        writers.append(VideoWriter("video", out / f"annotated{extension_for(codec)}", codec))
    if cfg.output.mask_video:
        writers.append(MaskVideoWriter(out, codec))
    if streams:
        writers.append(IntermediateWriter(out, streams, codec))
    if mask_images is not None:
        writers.append(MaskImagesWriter(Path(mask_images), force))
    if show is not None:
        writers.append(ViewerWriter(show))
    return writers


def follow_job(source: Any, cfg: PipelineConfig, out_dir: str | Path, tracker: SingleTracker,
               box: Box, name: str, *, params: dict[str, Any] | None = None,
               video: bool = True, force: bool = False, gt: Annotations | None = None,
               gt_id: int | None = None) -> Job:
    """``motiontrack follow``: ``tracks.txt`` (id 1), the annotated video, ``summary.json`` with
    the per-frame IoU against one ground-truth object when there is ground truth."""
    out = Path(out_dir)
    codec = cfg.output.codec

    def score(truth: Annotations, pred: Annotations, frames: int, start: int) -> dict[str, float]:
        from ..tracking.single import follow_accuracy

        return follow_accuracy(truth, replace(pred, meta={"last_frame": start + frames}), gt_id)

    def build(src: Source) -> Job:
        truth = gt if gt is not None else src.ground_truth()
        tracks = TracksWriter(out)
        writers = [tracks]
        if video:
            writers.append(VideoWriter("video", out / f"annotated{extension_for(codec)}", codec))
        if truth is not None:
            writers.append(ScoreWriter(out, truth, tracks, score, write_gt=False))
        return Job(src, FollowProcessor(tracker, box, name, params), writers, out, force=force)

    return _opened(source, cfg.source, build)


def sparse_flow_job(source: Any, cfg: PipelineConfig, out_dir: str | Path,
                    params: SparseFlowParams, *, force: bool = False,
                    gt: Annotations | None = None, scoring: str = DEFAULT_SCORING) -> Job:
    """``motiontrack flow --mode sparse``: ``tracks.txt``, the annotated video with feature
    trails, the mask video, ``summary.json`` (accuracy with ground truth, zero-marked rows
    counted as ``scoring`` names) and ``config.toml``."""
    out = Path(out_dir)
    ignores_zero_marked(scoring)
    codec = cfg.output.codec

    def build(src: Source) -> Job:
        truth = gt if gt is not None else src.ground_truth()
        tracks = TracksWriter(out)
        writers = [tracks]
        if cfg.output.video:
            writers.append(VideoWriter("video", out / f"annotated{extension_for(codec)}", codec))
        if cfg.output.mask_video:
            writers.append(MaskVideoWriter(out, codec))
        if truth is not None:
            from ..evaluate.score import score_run

            writers.append(ScoreWriter(out, truth, tracks,
                                       functools.partial(score_run, scoring=scoring),
                                       write_gt=False))
        return Job(src, SparseFlowProcessor(cfg, src.info, params), writers, out, force=force,
                   config=(save_config, cfg))

    return _opened(source, cfg.source, build)


def dense_flow_job(source: Any, cfg: PipelineConfig, out_dir: str | Path, *,
                   max_magnitude: float | None = None, force: bool = False) -> Job:
    """``motiontrack flow --mode dense``: the flow colour video ``flow<ext>``, the
    flow-magnitude mask video, ``summary.json`` with magnitude statistics."""
    out = Path(out_dir)
    codec = cfg.output.codec

    def build(src: Source) -> Job:
        writers = [VideoWriter("flow_video", out / f"flow{extension_for(codec)}", codec)]
        if cfg.output.mask_video:
            writers.append(MaskVideoWriter(out, codec))
        return Job(src, DenseFlowProcessor(cfg.motion.farneback, max_magnitude), writers, out,
                   force=force)

    return _opened(source, cfg.source, build)


def overlay_job(source: Any, out: str | Path | None, runs: Sequence[tuple[str, Annotations]],
                gt: Annotations | None = None, *, first: int = 1, last: int | None = None,
                png_frames: Iterable[int] = (), png_dir: str | Path | None = None,
                codec: str = "vp80", force: bool = False, fps: float = 0.0) -> Job:
    """``motiontrack overlay``: ground truth (given, or the source's own) and runs drawn over
    frames ``first`` to ``last`` (1-based, inclusive) as the video ``out`` (at ``fps``, 0 = the
    source's rate) and PNG stills of ``png_frames`` in ``png_dir`` (default: beside ``out``);
    no summary file."""
    png_frames = list(png_frames)
    if out is None and not png_frames:
        raise ConfigError("nothing to write: give an output video or --png-frames")
    if first < 1 or (last is not None and last < first):
        raise ConfigError(f"frame range must satisfy 1 <= first <= last, got {first}:{last}")
    video = Path(out) if out is not None else None
    stills = Path(png_dir) if png_dir is not None else (video.parent if video else Path("."))
    sc = SourceConfig(start=first - 1, max_frames=0 if last is None else last - first + 1,
                      fps=fps)

    def build(src: Source) -> Job:
        truth = gt if gt is not None else src.ground_truth()
        if truth is None and not runs:
            raise ConfigError("nothing to draw: give --gt and/or --pred")
        writers: list = [VideoWriter("video", video, codec)] if video is not None else []
        if png_frames:
            writers.append(StillsWriter(stills, png_frames))
        # the folder's lock as a run takes it: an overlay into a run's folder waits for no run
        return Job(src, OverlayProcessor(runs, truth, first, last), writers,
                   video.parent if video is not None else stills, force=force, summary=False,
                   own_folder=not (video is not None and is_stdout(video)))

    return _opened(source, sc, build)
