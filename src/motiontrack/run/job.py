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
* any other error (a bug, an encoder that cannot write): every output of this run is removed,
  temporary files included, so that nothing half-made blocks the retry, and the error is raised.

``config.toml`` and ``summary.json`` are written last, after every other output.
"""

from __future__ import annotations

import json
import logging
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Protocol, Sequence

import numpy as np

from ..errors import SourceError
from ..io.atomic import atomic_write_text, check_writable
from ..io.sources import Source, SourceInfo
from ..types import FrameResult

log = logging.getLogger(__name__)

__all__ = ["Job", "JobContext", "JobSummary", "Processor", "RunOutcome", "Writer"]


class RunOutcome:
    """How a processing loop ended, so its outputs can be finalised before the error surfaces.

    ``with RunOutcome() as outcome:`` around the loop: an interruption (``KeyboardInterrupt``) or a
    source that failed for good (:class:`SourceError`) ends the block instead of escaping it, and
    is recorded in :attr:`status`, :attr:`interrupted` and :attr:`error`. After the outputs are
    written, :meth:`reraise` lets it escape, so the command still exits with the right code.
    Other exceptions pass through untouched.
    """

    def __init__(self) -> None:
        self.status = "complete"
        self.interrupted = False
        self.error: SourceError | None = None

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
        return False

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

    def start(self, ctx: JobContext) -> None:
        """Called once before the first frame."""

    def write(self, result: FrameResult) -> None:
        """Called for every frame."""

    def close(self, keep: bool) -> None:
        """Finish the files: commit them (``keep``) or remove them and their temporary files."""

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
    out_dir : the output folder (created when the run starts).
    force : overwrite existing outputs.
    config : written to ``config.toml`` when the run ends (``(writer function, object)``), or None.
    summary : write ``summary.json`` (the summary is returned by :meth:`run` either way).
    """

    def __init__(self, source: Source, processor: Processor, writers: Sequence[Writer],
                 out_dir: str | Path, *, force: bool = False,
                 config: tuple[Callable[[Any, Path], None], Any] | None = None,
                 summary: bool = True) -> None:
        self.source = source
        self.processor = processor
        self.writers = list(writers)
        self.out = Path(out_dir)
        self.config = config
        self.paths: dict[str, Path] = {}
        for w in self.writers:
            self.paths.update(w.paths)
        if summary:
            self.paths["summary"] = self.out / "summary.json"
        if config is not None:
            self.paths["config"] = self.out / "config.toml"
        check_writable(list(self.paths.values()), force)

    @property
    def info(self) -> SourceInfo:
        return self.source.info

    def expected_frames(self) -> int | None:
        return self.source.expected_frames()

    def run(self, progress: Callable[[int], None] | None = None,
            should_stop: Callable[[], bool] | None = None) -> JobSummary:
        """Process the source and write the outputs.

        ``should_stop`` is polled after each complete frame (the CLI's signal handlers set it), so
        an interruption never splits a frame between the outputs.
        """
        info = self.info
        self.out.mkdir(parents=True, exist_ok=True)
        ctx = JobContext(self.out, info, self.processor, self.source)
        summary = JobSummary(source=info.name, width=info.width, height=info.height,
                             source_fps=info.fps)
        t0 = time.perf_counter()
        try:
            for w in self.writers:
                w.start(ctx)
            with RunOutcome() as outcome:
                self._loop(ctx, summary, progress, should_stop)
        except BaseException:
            self._close(keep=False)
            raise
        finally:
            summary.seconds = time.perf_counter() - t0
            self.source.close()
        self._close(keep=True)
        if outcome.status != "complete":
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
            atomic_write_text(self.paths["summary"],
                              json.dumps(summary.as_dict(), indent=2) + "\n")
        outcome.reraise()  # everything is written; an interrupt or a failed source still surfaces
        return summary

    def _loop(self, ctx: JobContext, summary: JobSummary,
              progress: Callable[[int], None] | None,
              should_stop: Callable[[], bool] | None) -> None:
        results = self.processor.results(self.source)
        try:
            for res in results:
                for w in self.writers:
                    w.write(res)
                summary.frames += 1
                if progress is not None:
                    progress(1)
                if ctx.stop_status is not None:
                    summary.status = ctx.stop_status
                    return
                if should_stop is not None and should_stop():
                    raise KeyboardInterrupt
        finally:
            close = getattr(results, "close", None)
            if close is not None:
                close()

    def _close(self, keep: bool) -> None:
        errors = []
        for w in self.writers:
            try:
                w.close(keep)
            except Exception as exc:   # close the others all the same
                errors.append(exc)
        if errors:
            raise errors[0]
