"""Output writers of a :class:`~motiontrack.run.job.Job`: one class per kind of output.

Each writer streams its file under a temporary name while the job runs and commits it when the
job closes it (or removes it when the job failed), so a file under its final name is always
complete. A new output of a command is one new writer here.
"""

from __future__ import annotations

import logging
import re
from collections import Counter
from pathlib import Path
from typing import Any, Callable, Iterable

import cv2
import numpy as np

from ..classify import CLASS_NAMES, class_id
from ..errors import InputError
from ..io.atomic import AtomicFile, DiskFullError, OutputLock, atomic_write_bytes, free_bytes
from ..io.mot import format_mot_rows, read_mot, write_mot
from ..io.video import DISK_RESERVE, VideoSink, check_codec, extension_for
from ..render.colors import TrackColors
from ..render.streams import parse_streams, stream_image
from ..tracking.gaps import fill_gaps
from ..types import Annotations, FrameResult, frame_number
from .folder import RunFolder
from .job import JobContext, JobSummary, Writer

log = logging.getLogger(__name__)

__all__ = ["TracksWriter", "RegionsWriter", "ScoreWriter", "VideoWriter", "MaskVideoWriter",
           "IntermediateWriter", "StillsWriter", "MaskImagesWriter", "ViewerWriter"]


class TracksWriter(Writer):
    """``tracks.txt``: MOTChallenge result rows, streamed frame by frame.

    Parameters
    ----------
    out : the output folder.
    camera : a calibrated camera: world positions (metres) of each box's foot point in columns
        8-9, and per-track speed, path length and height in ``summary.json``.
    max_gap : when the run ends, a track's gaps of up to this many frames are filled by
        interpolation (:func:`~motiontrack.tracking.gaps.fill_gaps`) and the file is rewritten
        sorted by frame, then id (None = the streamed file is final; see
        :func:`~motiontrack.pipeline.fill_gap_frames`).

    Rows of tracks confirmed in a frame at their earlier, tentative frames
    (:attr:`FrameResult.earlier`) are streamed as they come, out of frame order; the rewrite sorts
    them.

    Tracks with a class (``classes.enabled``, :attr:`Track.label`) get an 11th column, the class
    number (:data:`~motiontrack.classify.CLASS_IDS`) the track had in that row's frame (from
    its evidence up to then: ``analyze`` on the file sees the classes the run's rules saw);
    ``summary.json`` gets each track's class and confidence at its end (``classes``, the
    evidence of its whole life) and the tracks of each class (``class_counts``).
    """

    def __init__(self, out: Path, camera: Any = None, max_gap: int | None = None) -> None:
        self.paths = {"tracks": RunFolder(out).tracks}
        self.camera = camera
        self.max_gap = max_gap
        self.ids: set[int] = set()
        self.backfilled = 0
        self._file: AtomicFile | None = None
        self._final: Annotations | None = None
        self._fps = 25.0
        #: each classified track's latest class and confidence
        self.labels: dict[int, tuple[str, float]] = {}

    def start(self, ctx: JobContext) -> None:
        self._fps = ctx.fps
        self._file = AtomicFile(self.paths["tracks"])

    def write(self, result: FrameResult) -> None:
        rows = result.reported
        self.backfilled += len(result.earlier)
        if not rows:
            return
        boxes = np.array([t.box.as_array() for _, t in rows])
        tid = [t.id for _, t in rows]
        world = self._world(boxes) if self.camera is not None else None
        classes = None
        if rows[0][1].label:
            classes = [class_id(t.label) for _, t in rows]
            self.labels.update((t.id, (t.label, t.label_score)) for _, t in rows)
        self._file.write(format_mot_rows([frame_number(f) for f, _ in rows], tid, boxes,
                                         [t.score for _, t in rows], world, classes))
        self.ids.update(tid)

    def close(self, keep: bool) -> None:
        if self._file is not None:
            self._file.commit() if keep else self._file.discard()
            self._file = None

    def final(self) -> Annotations:
        """The finished tracks file as a table (read back once: nothing accumulates in memory
        per frame while the job runs)."""
        if self._final is None:
            self._final = read_mot(self.paths["tracks"], kind="results")
        return self._final

    def finish(self, summary: JobSummary) -> None:
        summary.tracks = len(self.ids)
        if self.max_gap is not None:
            self._complete(summary, self.max_gap)
        if self.labels:
            self._classes(summary)
        if self.camera is not None:
            from ..calibrate.measure import track_measurements   # with a camera only

            pred = self.final()
            summary.extra["measurements"] = {
                str(k): v for k, v in track_measurements(pred.frames, pred.ids, pred.boxes,
                                                         self.camera, self._fps).items()}

    def _complete(self, summary: JobSummary, max_gap: int) -> None:
        """Rewrite the file sorted by frame, then id, with each track's short gaps filled; the
        filled rows get their world position from the camera."""
        pred = self.final()
        filled = fill_gaps(pred, max_gap)
        summary.extra["backfilled_rows"] = self.backfilled
        summary.extra["filled_rows"] = len(filled) - len(pred)
        if self.camera is not None:
            new = (filled.world == -1.0).all(axis=1)
            filled.world[new] = self._world(filled.boxes[new])
        write_mot(filled, self.paths["tracks"], kind="results")   # sorted by frame, then id
        log.info("tracks.txt: %d rows at tentative frames, %d filled in gaps of up to %d frames",
                 self.backfilled, len(filled) - len(pred), max_gap)
        self._final = filled

    def _classes(self, summary: JobSummary) -> None:
        """Each track's class and confidence at its end, and the tracks of each class, in
        ``summary.json``."""
        summary.extra["classes"] = {str(tid): {"class": name, "confidence": conf}
                                    for tid, (name, conf) in sorted(self.labels.items())}
        counts = Counter(name for name, _ in self.labels.values())
        summary.extra["class_counts"] = {name: counts.get(name, 0) for name in CLASS_NAMES}

    def _world(self, boxes: np.ndarray) -> np.ndarray:
        """Ground-plane positions ``(x, y, 0)`` in metres of the boxes' foot points."""
        from ..calibrate.measure import world_positions   # with a camera only

        return np.column_stack([world_positions(boxes, self.camera), np.zeros(len(boxes))])


class RegionsWriter(Writer):
    """``regions.txt``: the motion regions of every frame as MOTChallenge rows (id = the region's
    number in its frame, from 1): what the detection stage found, for framewise scoring."""

    def __init__(self, out: Path) -> None:
        self.paths = {"regions": Path(out) / "regions.txt"}
        self._file: AtomicFile | None = None

    def start(self, ctx: JobContext) -> None:
        self._file = AtomicFile(self.paths["regions"])

    def write(self, result: FrameResult) -> None:
        if result.regions:
            boxes = np.array([r.box.as_array() for r in result.regions])
            n = len(result.regions)
            self._file.write(format_mot_rows([frame_number(result.index)] * n, range(1, n + 1),
                                             boxes, [r.score for r in result.regions]))

    def close(self, keep: bool) -> None:
        if self._file is not None:
            self._file.commit() if keep else self._file.discard()
            self._file = None


class ScoreWriter(Writer):
    """The run scored against ground truth (``summary.json``'s ``accuracy``) and, with
    ``write_gt``, the ground truth written as ``gt.txt`` beside the tracks.

    ``score(gt, pred, frames, start)`` gets the finished tracks of ``tracks`` (a
    :class:`TracksWriter` before this writer in the job), the frames processed and the source's
    first frame index.
    """

    def __init__(self, out: Path, gt: Annotations, tracks: TracksWriter,
                 score: Callable[[Annotations, Annotations, int, int], dict[str, float]],
                 write_gt: bool = True) -> None:
        self.paths = {"gt": RunFolder(out).gt} if write_gt else {}
        self.gt = gt
        self.tracks = tracks
        self.score = score
        self._start = 0

    def start(self, ctx: JobContext) -> None:
        self._start = ctx.start

    def finish(self, summary: JobSummary) -> None:
        summary.accuracy = self.score(self.gt, self.tracks.final(), summary.frames, self._start)
        if "gt" in self.paths:
            write_mot(self.gt, self.paths["gt"], kind="gt")


class VideoWriter(Writer):
    """A video of one picture per frame: by default the processor's annotated frame
    (:meth:`~motiontrack.run.job.Processor.annotate`), or ``picture(result)`` (frames where it
    gives None are skipped)."""

    large = True

    def __init__(self, key: str, path: Path, codec: str,
                 picture: Callable[[FrameResult], np.ndarray | None] | None = None) -> None:
        check_codec(codec)   # before the run: an encoder this installation lacks
        self.paths = {key: Path(path)}
        self.codec = codec
        self.picture = picture
        self._sink: VideoSink | None = None
        self._ctx: JobContext | None = None

    def start(self, ctx: JobContext) -> None:
        self._ctx = ctx
        (path,) = self.paths.values()
        self._sink = VideoSink(path, ctx.fps, self.codec)

    def write(self, result: FrameResult) -> None:
        img = (self._ctx.annotated(result) if self.picture is None else self.picture(result))
        if img is not None:
            self._sink.write(img)

    def close(self, keep: bool) -> None:
        if self._sink is not None:
            self._sink.close() if keep else self._sink.discard()
            self._sink = None


def MaskVideoWriter(out: Path, codec: str) -> VideoWriter:
    """``mask<ext>``: the cleaned motion mask of every frame (processing scale)."""
    return VideoWriter("mask_video", Path(out) / f"mask{extension_for(codec)}", codec,
                       picture=lambda r: r.mask)


class IntermediateWriter(Writer):
    """Intermediate movies (``--save background,difference,motion,annotated``): one video per
    stream of :mod:`motiontrack.render.streams`, named after it."""

    large = True

    def __init__(self, out: Path, streams: Iterable[str] | str, codec: str) -> None:
        self.streams = parse_streams(streams)
        self.paths = {s: Path(out) / f"{s}{extension_for(codec)}" for s in self.streams}
        check_codec(codec)
        self.codec = codec
        self._sinks: dict[str, VideoSink] = {}
        self._ctx: JobContext | None = None

    def start(self, ctx: JobContext) -> None:
        self._ctx = ctx
        self._sinks = {s: VideoSink(p, ctx.fps, self.codec) for s, p in self.paths.items()}
        # fed the same tracks frame by frame, it gives them the colours of the annotated video
        self._colors = TrackColors()

    def write(self, result: FrameResult) -> None:
        colors = self._colors.assign(t.id for t in result.tracks)
        for s, sink in self._sinks.items():
            img = stream_image(s, result, self._ctx.processor.background(), colors=colors)
            if img is not None:
                sink.write(img)

    def close(self, keep: bool) -> None:
        sinks, self._sinks = list(self._sinks.values()), {}
        try:
            for i, sink in enumerate(sinks):
                sink.close() if keep else sink.discard()
        except BaseException:  # one cannot be finished: the others go too
            for sink in sinks[i:]:
                sink.discard()
            raise


class StillsWriter(Writer):
    """PNG stills of the annotated picture at chosen 1-based frame numbers, as
    ``folder/frame_%06d.png`` (each written atomically when its frame comes); frames the run
    never reaches are named in a warning when it ends."""

    large = True

    def __init__(self, folder: Path, frames: Iterable[int]) -> None:
        self.folder = Path(folder)
        self.wanted = sorted({int(f) for f in frames})
        self.paths = {f"frame_{f}": self.folder / f"frame_{f:06d}.png" for f in self.wanted}
        self.written: list[str] = []
        self._ctx: JobContext | None = None

    def start(self, ctx: JobContext) -> None:
        self._ctx = ctx

    def write(self, result: FrameResult) -> None:
        path = self.paths.get(f"frame_{frame_number(result.index)}")
        if path is not None:
            ok, buf = cv2.imencode(".png", self._ctx.annotated(result))
            if ok:
                atomic_write_bytes(path, buf.tobytes())
                self.written.append(str(path))

    def close(self, keep: bool) -> None:
        if not keep:
            for p in self.written:
                Path(p).unlink(missing_ok=True)

    def finish(self, summary: JobSummary) -> None:
        missing = [f for f in self.wanted if str(self.paths[f"frame_{f}"]) not in self.written]
        if missing:
            log.warning("--png-frames outside the rendered frames: %s",
                        ", ".join(map(str, missing)))


class MaskImagesWriter(Writer):
    """``--mask-images DIR``: the cleaned motion mask of every frame as ``DIR/bin%06d.png``,
    0/255 single channel at the source's size (a mask found at a reduced processing scale is
    enlarged by nearest neighbour), numbered as CDnet numbers its input: frame index + 1, so the
    first frame of a run started at 0-based ``start`` is ``bin{start + 1:06d}.png``.
    ``motiontrack evaluate-masks --pred DIR`` reads the folder as it is.

    The folder follows the rules of the job's own: it is refused when it holds mask images
    already, unless ``force`` (they are then removed when the run starts, so that two runs never
    mix); a folder other than the job's is locked for the run; each image is written atomically
    when its frame comes and stays when the run is stopped; a failed run, or a full device (a
    large output, like the videos), removes the images this run wrote.
    """

    large = True
    #: the names written here and the temporary names of :func:`atomic_write_bytes` for them
    NAME = re.compile(r"bin\d{6}\.png")
    TEMP = re.compile(r"\.bin\d{6}\.png\.[a-z0-9_]{8}\.part")

    def __init__(self, folder: Path, force: bool = False) -> None:
        self.folder = Path(folder)
        self.force = force
        self.paths = {}   # one file per frame: this writer removes its own (close, not the job)
        self.written: list[Path] = []
        self._size: tuple[int, int] = (0, 0)
        self._lock: OutputLock | None = None
        self._refuse_existing()   # at once: nothing has been processed yet

    def _existing(self) -> list[Path]:
        if not self.folder.is_dir():
            return []
        return sorted(p for p in self.folder.iterdir() if self.NAME.fullmatch(p.name))

    def _refuse_existing(self) -> None:
        if self.folder.exists() and not self.folder.is_dir():
            raise InputError(f"--mask-images {self.folder} is not a folder")
        old = self._existing()
        if old and not self.force:
            raise InputError(f"output exists: {self.folder} holds {len(old)} mask image(s) "
                             f"({old[0].name} ...) (use --force to overwrite)")

    def start(self, ctx: JobContext) -> None:
        self._size = (ctx.info.width, ctx.info.height)
        if self.folder.resolve() != ctx.out.resolve():   # the job's own folder is locked
            self._lock = OutputLock(self.folder)
        self._refuse_existing()   # again, now that no other run can write here
        for p in self.folder.iterdir():   # a killed run's temporary files, the old images
            if (self.TEMP.fullmatch(p.name) or (self.force and self.NAME.fullmatch(p.name))) \
                    and p.is_file() and not p.is_symlink():
                p.unlink(missing_ok=True)

    def write(self, result: FrameResult) -> None:
        if result.mask is None:
            return   # external detections: track_job refuses --mask-images with them
        mask = result.mask if result.mask.dtype == bool else result.mask == 255
        img = np.where(mask, np.uint8(255), np.uint8(0))
        if img.shape[::-1] != self._size:
            img = cv2.resize(img, self._size, interpolation=cv2.INTER_NEAREST)
        path = self.folder / f"bin{frame_number(result.index):06d}.png"
        free = free_bytes(self.folder)
        if free < DISK_RESERVE:   # leave room for the small outputs, as a video does
            raise DiskFullError(path, f"{free // 1024} KiB left on the device, less than the "
                                      f"{DISK_RESERVE // 1024} KiB the mask images leave for "
                                      "the other outputs")
        ok, buf = cv2.imencode(".png", img)
        if not ok:  # pragma: no cover - a 2-D uint8 image always encodes
            raise RuntimeError(f"cannot encode {path.name}")
        atomic_write_bytes(path, buf.tobytes())
        self.written.append(path)

    def close(self, keep: bool) -> None:
        if not keep:   # also after a commit: a later failure removes every output of the run
            for p in self.written:
                p.unlink(missing_ok=True)
            self.written = []
        if self._lock is not None:
            self._lock.release()
            self._lock = None

    def finish(self, summary: JobSummary) -> None:
        frames = sorted(int(p.stem[3:]) for p in self.written)
        summary.extra["mask_images"] = {
            "folder": str(self.folder), "images": len(frames),
            "first": frames[0] if frames else None, "last": frames[-1] if frames else None}


class ViewerWriter(Writer):
    """A live view: ``show(image)`` with every annotated frame; when it returns False the run
    ends after this frame with status ``"stopped by user"``."""

    def __init__(self, show: Callable[[np.ndarray], bool]) -> None:
        self.paths = {}
        self.show = show
        self._ctx: JobContext | None = None

    def start(self, ctx: JobContext) -> None:
        self._ctx = ctx

    def write(self, result: FrameResult) -> None:
        if not self.show(self._ctx.annotated(result)):
            self._ctx.request_stop("stopped by user")
