"""The one job loop: a source, a per-frame processor and a set of output writers.

Every command that processes video (``track``, ``follow``, ``flow``, the runs of ``sweep``,
``tune`` and ``ablate``) builds a :class:`Job` and calls :meth:`Job.run`::

    job = Job(source, processor, [TracksWriter(...), VideoWriter(...)], out_dir, force=force)
    summary = job.run(progress=bar.update, should_stop=signals.stop)

The job refuses to overwrite existing outputs unless ``force``, streams every frame to every
writer, and finalises the outputs whatever ends the run:

* the source ends: every writer commits its file, ``summary.json`` says ``"complete"``;
* an interruption (``should_stop`` after a complete frame, or ``KeyboardInterrupt`` mid-frame) or
  a source that fails for good (:class:`~motiontrack.errors.SourceError`): the outputs hold every
  frame processed so far, ``summary.json`` records the status, then the interruption or the error
  is raised again (:class:`RunOutcome`);
* the device fills (:class:`~motiontrack.io.atomic.DiskFullError`): the large outputs (videos,
  stills; :attr:`Writer.large`) are removed, the small ones (tracks, summary) hold every frame
  processed so far when they fit, and the error is raised; when they do not fit, nothing is kept;
* any other error (a bug, an encoder that cannot write): every output of this run is removed,
  temporary files included, so that nothing half-made blocks the retry, and the error is raised.

``config.toml`` and ``summary.json`` are written last, after every other output.

A job that writes ``summary.json`` owns its output folder while it exists: a lock
(:class:`~motiontrack.io.atomic.OutputLock`) refuses a second run into the folder at once, every
temporary file a killed run left there is removed (whatever output it was for), and with ``force`` the old outputs (the
files this job writes and those the old ``summary.json`` lists) are removed before the run
starts, so that the folder never holds a mixture of two runs.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Protocol, Sequence

import numpy as np

from ..errors import SourceError
from ..io.atomic import (DiskFullError, OutputLock, check_writable, remove_folder_temps,
                         remove_leftover_temps, remove_outputs)
from ..io.sources import Source, SourceInfo
from ..types import FrameResult
from .folder import RunFolder

log = logging.getLogger(__name__)

__all__ = ["Job", "JobContext", "JobSummary", "Processor", "RunOutcome", "Writer"]


class RunOutcome:
    """How a processing loop ended, so its outputs can be finalised before the error surfaces.

    ``with RunOutcome() as outcome:`` around the loop: an interruption (``KeyboardInterrupt``), a
    source that failed for good (:class:`SourceError`) or a full device (:class:`DiskFullError`,
    :attr:`disk_full`) ends the block instead of escaping it, and is recorded in :attr:`status`,
    :attr:`interrupted` and :attr:`error`. After the outputs are
    written, :meth:`reraise` lets it escape, so the command still exits with the right code.
    Other exceptions pass through untouched.
    """

    def __init__(self) -> None:
        self.status = "complete"
        self.interrupted = False
        self.error: SourceError | DiskFullError | None = None

    def __enter__(self) -> "RunOutcome":
        return self

    def __exit__(self, typ, exc, tb) -> bool:
        if typ is None:
            return False
        if issubclass(typ, KeyboardInterrupt):
            self.interrupted, self.status = True, "interrupted"
            return True
        if issubclass(typ, SourceError):
            self.error, self.status = exc, f"source failed: {exc}"
            return True
        if issubclass(typ, DiskFullError):
            self.error, self.status = exc, str(exc)
            return True
        return False

    @property
    def disk_full(self) -> bool:
        return isinstance(self.error, DiskFullError)

    @property
    def failed(self) -> bool:
        return self.error is not None

    def reraise(self) -> None:
        if self.interrupted:
            raise KeyboardInterrupt
        if self.error is not None:
            raise self.error


@dataclass
class JobSummary:
    """What ``summary.json`` holds: the common fields, then the processor's and the writers'
    entries (:attr:`extra`) and the accuracy when ground truth was given."""

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


class Processor(Protocol):
    """The per-frame work of a job (:mod:`motiontrack.run.processors`)."""

    def results(self, source: Source) -> Iterator[FrameResult]:
        """One result per frame of ``source``."""

    def annotate(self, result: FrameResult) -> np.ndarray:
        """The annotated picture of the result just yielded (BGR, for the video writer)."""

    def background(self) -> np.ndarray | None:
        """The motion stage's current background image, when it has one."""

    def summary(self) -> dict[str, Any]:
        """The processor's own entries of ``summary.json``."""


@dataclass
class JobContext:
    """What writers learn about the job when it starts."""

    out: Path
    info: SourceInfo
    processor: Processor
    source: Source
    #: set by a writer (e.g. the live viewer) to end the run after the current frame
    stop_status: str | None = None
    _picture: tuple[FrameResult, np.ndarray] | None = field(default=None, repr=False)

    @property
    def fps(self) -> float:
        """The source's frame rate (25 when unknown), for videos and durations."""
        return self.info.fps or 25.0

    @property
    def start(self) -> int:
        return getattr(self.source, "start", 0)

    def request_stop(self, status: str) -> None:
        self.stop_status = status

    def annotated(self, result: FrameResult) -> np.ndarray:
        """The processor's annotated picture of ``result``, drawn once however many writers
        want it (the video and the live view)."""
        if self._picture is None or self._picture[0] is not result:
            self._picture = (result, self.processor.annotate(result))
        return self._picture[1]


class Writer:
    """One output of a job. Subclasses set :attr:`paths` (name → file) in ``__init__`` and
    implement the hooks they need; every hook has a default that does nothing."""

    paths: dict[str, Path]
    #: a large output (a video, stills): the first to go when the device fills, to make room
    #: for the small ones
    large: bool = False

    def start(self, ctx: JobContext) -> None:
        """Called once before the first frame."""

    def write(self, result: FrameResult) -> None:
        """Called for every frame. :class:`DiskFullError` says the device is full; a small
        writer then keeps what it could not write, to write it when it is closed with ``keep``."""

    def close(self, keep: bool) -> None:
        """Finish the files: commit them (``keep``) or remove them and their temporary files
        (without ``keep`` it must not fail: another error is on its way)."""

    def finish(self, summary: JobSummary) -> None:
        """Called after every writer is closed with ``keep``, in writer order: post-processing
        of the committed files and entries of ``summary.json``."""


class Job:
    """A source, a processor and writers, run once (see the module docstring).

    Parameters
    ----------
    source : an open :class:`Source` (the job closes it).
    processor : the per-frame work.
    writers : the outputs, in the order they receive frames and finish.
    out_dir : the output folder (created when the run starts, or at once when the job owns it).
    force : replace existing outputs (they are removed when the run starts).
    config : written to ``config.toml`` when the run ends (``(writer function, object)``), or None.
    summary : write ``summary.json`` (the summary is returned by :meth:`run` either way).
    own_folder : hold the folder's lock from now until the run ends (default: with ``summary``;
        ``overlay`` writes no summary but holds the lock of its video's folder, a run's often).
    layout : what ``summary.json`` holds, made of the run's :class:`JobSummary` (default
        :meth:`JobSummary.as_dict`; ``analyze`` keeps the fields of a tracks file's analysis).
    replace_listed : with ``force``, also remove the outputs the folder's old ``summary.json``
        lists (a run of the same command with other settings may have written files this one
        does not). A job that adds its outputs to another run's folder, as ``analyze`` does to
        the folder of the tracks it reads, says False: there they are that run's files.
    """

    def __init__(self, source: Source, processor: Processor, writers: Sequence[Writer],
                 out_dir: str | Path, *, force: bool = False,
                 config: tuple[Callable[[Any, Path], None], Any] | None = None,
                 summary: bool = True, own_folder: bool | None = None,
                 layout: Callable[[JobSummary], dict[str, Any]] = JobSummary.as_dict,
                 replace_listed: bool = True) -> None:
        self.source = source
        self.processor = processor
        self.writers = list(writers)
        self.out = Path(out_dir)
        self.config = config
        self.layout = layout
        self.paths: dict[str, Path] = {}
        for w in self.writers:
            self.paths.update(w.paths)
        self.folder = RunFolder(self.out)
        if summary:
            self.paths["summary"] = self.folder.summary_path
        if config is not None:
            self.paths["config"] = self.folder.config
        self.force = force
        self.replace_listed = replace_listed
        own = summary if own_folder is None else own_folder
        self._lock = OutputLock(self.out) if own else None
        try:
            check_writable(list(self.paths.values()), force)
        except BaseException:
            self._release()
            raise

    @property
    def info(self) -> SourceInfo:
        return self.source.info

    def expected_frames(self) -> int | None:
        return self.source.expected_frames()

    def run(self, progress: Callable[[int], None] | None = None,
            should_stop: Callable[[], bool] | None = None) -> JobSummary:
        """Process the source and write the outputs.

        ``should_stop`` is polled after each complete frame (the CLI's signal handlers set it), so
        an interruption never splits a frame between the outputs. The source polls it too
        (:attr:`Source.stop_requested`) while it waits for a frame, so that a live stream backing
        off, reconnecting or stalled ends the run as soon as a stop is asked.
        """
        info = self.info
        self.out.mkdir(parents=True, exist_ok=True)
        ctx = JobContext(self.out, info, self.processor, self.source)
        summary = JobSummary(source=info.name, width=info.width, height=info.height,
                             source_fps=info.fps)
        if info.stored_fps is not None:   # source.fps set: the rate the file states, for the record
            summary.extra["source_stored_fps"] = info.stored_fps
        t0 = time.perf_counter()
        if should_stop is not None:
            self.source.stop_requested = should_stop
        try:
            self._clear_folder()
            for w in self.writers:
                w.start(ctx)
            with RunOutcome() as outcome:
                self._loop(ctx, summary, progress, should_stop)
        except BaseException:
            self._fail()
            raise
        finally:
            summary.seconds = time.perf_counter() - t0
            self.source.close()
        try:
            self._write_results(summary, outcome)
        except BaseException:
            self._fail()
            raise
        outcome.reraise()  # everything is written; an interrupt or a failed source still surfaces
        return summary

    def _write_results(self, summary: JobSummary, outcome: RunOutcome) -> None:
        """Commit the outputs, post-process them, write ``config.toml`` and ``summary.json``."""
        if not outcome.disk_full:
            try:
                self._close(keep=True, large_only=True)
            except DiskFullError as exc:  # a video could not be finished
                outcome.error, outcome.status = exc, str(exc)
        if outcome.disk_full:  # the large outputs go first, to make room for the small ones
            self._remove_large(summary.frames)
        self._close(keep=True)
        if outcome.status != "complete":
            if not outcome.disk_full:
                log.warning("%s after %d frames; writing what was processed", outcome.status,
                            summary.frames)
            summary.status = outcome.status
        summary.interrupted = outcome.interrupted
        summary.truncated = summary.truncated or self.source.truncated or outcome.failed
        summary.extra.update(self.processor.summary())
        for w in self.writers:
            w.finish(summary)
        if self.config is not None:
            save, cfg = self.config
            save(cfg, self.paths["config"])
        summary.outputs = {k: str(v) for k, v in self.paths.items()
                           if v.exists() or k == "summary"}
        if "summary" in self.paths:
            self.folder.write_summary(self.layout(summary))
        self._release()

    def _loop(self, ctx: JobContext, summary: JobSummary,
              progress: Callable[[int], None] | None,
              should_stop: Callable[[], bool] | None) -> None:
        results = self.processor.results(self.source)
        try:
            for res in results:
                full = self._write(res)
                summary.frames += 1
                if progress is not None:
                    progress(1)
                if full is not None:
                    raise full   # the frame is in every output that is kept
                if ctx.stop_status is not None:
                    summary.status = ctx.stop_status
                    return
                if should_stop is not None and should_stop():
                    raise KeyboardInterrupt
            if should_stop is not None and should_stop():
                raise KeyboardInterrupt   # the source ended early because a stop was asked
        finally:
            close = getattr(results, "close", None)
            if close is not None:
                close()

    def _write(self, result: FrameResult) -> DiskFullError | None:
        """Give one frame to every writer. When the device is full, the frame still goes to
        every small writer (the large ones are removed when the run ends) and the error is
        returned."""
        full = None
        for w in self.writers:
            if full is not None and w.large:
                continue
            try:
                w.write(result)
            except DiskFullError as exc:
                full = full or exc
        return full

    def _close(self, keep: bool, large_only: bool = False) -> None:
        errors = []
        for w in self.writers:
            if large_only and not w.large:
                continue
            try:
                w.close(keep)
            except Exception as exc:   # close the others all the same
                errors.append(exc)
        if errors and keep:
            raise errors[0]
        for exc in errors:           # removing: the error on its way matters, not this one
            log.debug("removing an output: %s", exc)

    def _remove_large(self, frames: int) -> None:
        """Remove the large outputs (temporary or committed) to make room for the small ones."""
        self._close(keep=False, large_only=True)
        removed = []
        for w in self.writers:
            for p in (w.paths.values() if w.large else ()):
                if p.is_file() and not p.is_symlink():
                    p.unlink(missing_ok=True)
                removed.append(p.name)
        # a job without summary.json (overlay, a sweep's run in a temporary folder) keeps
        # nothing for the user: the error alone reports the full device
        (log.warning if "summary" in self.paths else log.debug)(
            "the device is full after %d frames: no %s; writing the other outputs",
            frames, ", ".join(removed) or "large outputs")

    def _clear_folder(self) -> None:
        """Before the first output appears: remove the temporary files a killed run left (in the
        folder, and those of this job's outputs elsewhere) and,
        with ``force``, the old outputs (of this job, and those the old summary lists)."""
        old = self._old_outputs() if self.force and self.replace_listed else []
        if self._lock is not None:  # no other run writes into the folder now
            # every temporary file a killed run left in the folder goes, not only those of the
            # outputs this job writes (a run with a video, killed, then one without)
            remove_folder_temps(self.out)
            remove_leftover_temps([*self.paths.values(), *old])
        if self.force:
            remove_outputs([*self.paths.values(), *old])

    def _old_outputs(self) -> list[Path]:
        """The outputs the ``summary.json`` in the folder lists, by name in this folder (a run
        with other settings may have written files this one does not)."""
        if "summary" not in self.paths:
            return []
        try:
            listed = (self.folder.summary() or {})["outputs"].values()
        except (AttributeError, KeyError, TypeError):
            return []
        names = {Path(str(v)).name for v in listed}
        paths = [self.out / n for n in sorted(names) if n and not n.startswith(".")]
        return [p for p in paths if p.is_file() and not p.is_symlink()]

    def _fail(self) -> None:
        """The run failed: remove every output of this run (none of them existed before it, or
        ``force`` removed the old ones), temporary files included, and free the folder."""
        self._close(keep=False)
        for p in self.paths.values():
            if p.is_file() and not p.is_symlink():
                p.unlink(missing_ok=True)
        self._release()

    def _release(self) -> None:
        if self._lock is not None:
            self._lock.release()
