"""``motiontrack batch``: one ``track`` run per video on Dask workers, an index of them all.

Each video runs as :func:`~motiontrack.run.jobs.track_job` into ``RESULTS/.<name>.partial`` and
the folder is renamed to ``RESULTS/<name>`` when the run is complete, so a results folder is
always a finished run. ``RESULTS/index.csv`` is rewritten (atomically) each time a video
finishes. A video that cannot be read is a ``failed`` row; the batch goes on.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import logging
import threading
import time
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

from ..config import PipelineConfig, apply_overrides, from_dict, load_config, to_dict
from ..errors import ConfigError, printable
from ..io.atomic import (DiskFullError, OutputLock, atomic_write_bytes, atomic_write_text,
                         remove_folder_temps)
from ..io.event_store import STORE_NAME
from ..run.executor import dask_client, map_tasks
from ..run.folder import RunFolder
from ..version import __version__
from .combined import COMBINED_FILE, write_combined
from .counts import COUNTS_FILE, TOTALS_FILE, write_counts
from .events import write_event_store
from .sources import Video, expand_sources, with_files

log = logging.getLogger(__name__)

__all__ = ["INDEX_FILE", "INDEX_COLUMNS", "BatchTask", "run_video", "run_batch", "config_hash"]

INDEX_FILE = "index.csv"
PARQUET_FILE = "index.parquet"
#: the files a batch writes at the root of RESULTS: no video may be named as one of them
BATCH_FILES = (INDEX_FILE, PARQUET_FILE, COMBINED_FILE, COUNTS_FILE, TOTALS_FILE, STORE_NAME)
INDEX_COLUMNS = ("name", "source", "status", "error", "frames", "fps", "tracks", "wall_s",
                 "worker", "attempts", "config_hash", "motiontrack_version", "opencv_version",
                 "HOTA", "MOTA", "IDF1")
METRICS = ("HOTA", "MOTA", "IDF1")


def config_hash(cfg: PipelineConfig) -> str:
    """The first 16 hex digits of the SHA-256 of the resolved config (canonical JSON)."""
    text = json.dumps(to_dict(cfg), sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


@dataclass(frozen=True)
class BatchTask:
    """Everything a worker needs for one video (picklable, self-contained)."""

    video: Video
    results: str
    config: Mapping[str, Any]
    config_hash: str
    timeout_s: float | None = None
    #: the Dask event topic the worker reports the video's frames on (None: no reports)
    progress_topic: str | None = None
    #: the name of the batch's ``distributed.Event`` that asks running videos to stop
    stop_event: str | None = None


#: seconds between two reports of a video's frames to the batch's client
REPORT_EVERY_S = 1.0


class VideoTimeout(Exception):
    """A video ran longer than the batch's ``--timeout-s``."""


class BatchStopped(Exception):
    """The batch was interrupted while this video ran."""


def _worker_name() -> str:
    worker = _this_worker()
    return "local" if worker is None else str(worker.name)


def _this_worker() -> Any:
    try:
        from distributed import get_worker

        return get_worker()
    except (ImportError, ValueError):   # not on a Dask worker
        return None


class _Frames:
    """The run's progress callback, which counts the frames and reports them on the batch's
    topic every :data:`REPORT_EVERY_S` seconds, and its stop poll: true once the video is over
    its time or the batch's stop event is set (checked as often as frames are reported), so
    that an interrupted batch frees even the workers of a remote cluster within a second or
    two (Dask cannot stop a running task)."""

    def __init__(self, task: BatchTask, deadline: float | None) -> None:
        self.name, self.deadline = task.video.name, deadline
        self.worker = _this_worker() if task.progress_topic or task.stop_event else None
        self.topic = task.progress_topic
        # the event is looked up at the first check, a second in: a short video never needs it
        self.stop_name = task.stop_event if self.worker is not None else None
        self.stop_event: Any = None
        self.frames, self.late, self.stopped = 0, False, False
        self.next_report = self.next_check = time.perf_counter() + REPORT_EVERY_S

    def __call__(self, n: int) -> None:
        self.frames += n
        if self.topic and self.worker is not None and time.perf_counter() >= self.next_report:
            self.next_report = time.perf_counter() + REPORT_EVERY_S
            try:
                self.worker.log_event(self.topic, {"name": self.name, "frames": self.frames})
            except Exception:   # noqa: BLE001 - progress is never worth failing a video
                self.topic = None

    def should_stop(self) -> bool:
        now = time.perf_counter()
        self.late = self.late or (self.deadline is not None and now > self.deadline)
        if self.stop_name is not None and now >= self.next_check:
            self.next_check = now + REPORT_EVERY_S
            try:
                if self.stop_event is None:
                    from distributed import Event

                    self.stop_event = Event(self.stop_name)
                self.stopped = self.stopped or self.stop_event.is_set()
            except Exception:   # noqa: BLE001 - the scheduler away: the client is gone too
                self.stop_name = None
        return self.late or self.stopped

    def batch_stopped(self) -> bool:
        """Whether the batch asked its videos to stop, its event checked now (not a second
        after the last check)."""
        self.next_check = 0.0
        self.should_stop()
        return self.stopped


def _one_line(exc: BaseException) -> str:
    text = printable(exc).splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".strip()


def _run_track_job(task: BatchTask, partial: Path, t0: float) -> Any:
    """Run the video's ``track`` job into ``partial``: its summary. :class:`VideoTimeout` when
    it ran over ``--timeout-s``, :class:`BatchStopped` when the batch asked it to stop."""
    from ..io.annotations import read_ground_truth
    from ..run.jobs import track_job

    v = task.video
    overrides = [f"measure.camera={json.dumps(v.camera)}"] if v.camera else []
    cfg = apply_overrides(from_dict(PipelineConfig, dict(task.config)), overrides)
    gt = read_ground_truth(v.gt) if v.gt else None
    job = track_job(v.source, cfg, partial, force=True, gt=gt, scene=v.scene)
    frames = _Frames(task, None if task.timeout_s is None else t0 + task.timeout_s)
    # polled after each frame: a run over its time stops itself, so its worker is free
    try:
        return job.run(progress=frames, should_stop=frames.should_stop)
    except KeyboardInterrupt:
        if frames.late:
            raise VideoTimeout(f"ran longer than --timeout-s {task.timeout_s:g}") from None
        if frames.stopped:
            raise BatchStopped("the batch stopped before this video finished") from None
        raise
    except Exception:
        # the batch stopped: the client removes the partial folder of the videos not done,
        # maybe while this run writes or commits into it; the error that gives is the stop's
        if frames.stopped or frames.batch_stopped():
            raise BatchStopped("the batch stopped before this video finished") from None
        raise


def run_video(task: BatchTask, attempt: int = 1) -> dict[str, Any]:
    """Run one video into ``RESULTS/<name>`` and return its index row; every error becomes a
    ``failed`` row (its partial folder removed), only an interruption propagates."""
    import cv2

    v = task.video
    out = Path(task.results)
    final = RunFolder(out / v.name)
    partial = final.partial()
    t0 = time.perf_counter()
    row: dict[str, Any] = {"name": v.name, "source": v.source, "status": "failed", "error": "",
                           "worker": _worker_name(), "attempts": attempt,
                           "config_hash": task.config_hash, "motiontrack_version": __version__,
                           "opencv_version": cv2.__version__}
    try:
        partial.remove()   # of a killed attempt
        summary = _run_track_job(task, partial.path, t0)
        # what --resume checks: the outputs as committed, and whose run they are
        final.commit_partial({"batch": {"name": v.name, "source": v.source,
                                        "config_hash": task.config_hash,
                                        "files": partial.digests()}})
        row.update(status="truncated" if summary.truncated else "done", frames=summary.frames,
                   fps=round(summary.fps, 3), tracks=summary.tracks)
        if summary.truncated:
            row["error"] = (f"the source ended early, after {summary.frames} frames; the "
                            "results hold them")
        row.update({k: summary.accuracy[k] for k in METRICS if k in (summary.accuracy or {})})
    except Exception as exc:   # noqa: BLE001 - one bad video never stops the batch
        partial.remove()
        if isinstance(exc, VideoTimeout):
            row["status"] = "timeout"
        elif isinstance(exc, BatchStopped):
            row["status"] = "interrupted"
        row["error"] = _one_line(exc)
        log.warning("%s %s: %s", v.name, row["status"], row["error"])
    row["wall_s"] = round(time.perf_counter() - t0, 3)
    return row


def _unfinished_row(task: BatchTask, status: str, error: str, **extra: Any) -> dict[str, Any]:
    """The row of a video that did not finish on a worker (its partial folder removed)."""
    import cv2

    v = task.video
    RunFolder(Path(task.results) / v.name).partial().remove()
    return {"name": v.name, "source": v.source, "status": status, "error": error, **extra,
            "config_hash": task.config_hash, "motiontrack_version": __version__,
            "opencv_version": cv2.__version__}


def _lost_row(task: BatchTask, exc: BaseException, attempts: int) -> dict[str, Any]:
    """The ``failed`` row of a video whose worker died on every attempt."""
    return _unfinished_row(task, "failed", f"its worker died on each of {attempts} attempts "
                                           f"({_one_line(exc)})", attempts=attempts)


def _hung_row(task: BatchTask, attempts: int) -> dict[str, Any]:
    """The ``timeout`` row of a video whose run did not stop itself (stuck inside a frame), so
    that its worker was restarted."""
    return _unfinished_row(task, "timeout", f"VideoTimeout: ran longer than --timeout-s "
                                            f"{task.timeout_s:g} and did not stop; worker "
                                            f"restarted", attempts=attempts)


def _ask_to_stop(client: Any, name: str) -> None:
    """Set the batch's stop event: its videos still running stop after their current frame."""
    try:
        from distributed import Event

        Event(name, client=client).set()
    except Exception as exc:   # noqa: BLE001 - the cluster gone: nothing runs to stop
        log.debug("could not ask the workers to stop: %s", exc)


def _interrupted_row(task: BatchTask) -> dict[str, Any]:
    """The row of a video the batch stopped before it finished (redone by ``--resume``)."""
    return _unfinished_row(task, "interrupted", "the batch stopped before this video finished")


class _Rate:
    """Frames tracked per video and the cluster's frame rate over the last
    :attr:`WINDOW_S` seconds."""

    WINDOW_S = 5.0

    def __init__(self) -> None:
        self.frames: dict[str, int] = {}
        self.samples: list[tuple[float, int]] = [(time.monotonic(), 0)]

    def seen(self, name: str, frames: int) -> None:
        self.frames[name] = max(frames, self.frames.get(name, 0))
        now = time.monotonic()
        self.samples.append((now, self.total()))
        while len(self.samples) > 2 and now - self.samples[1][0] > self.WINDOW_S:
            self.samples.pop(0)

    def total(self) -> int:
        return sum(self.frames.values())

    def fps(self) -> float:
        (t0, n0), (t1, n1) = self.samples[0], self.samples[-1]
        return (n1 - n0) / (t1 - t0) if t1 > t0 else 0.0


def _complete(results: Path, video: Video, chash: str) -> dict[str, Any] | None:
    """The summary of ``RESULTS/<name>`` when it holds a complete, untruncated run of
    ``video`` made with the config ``chash`` whose outputs are as the batch committed them;
    None (with a warning when the folder was changed) when the video must run again."""
    folder = RunFolder(results / video.name)
    meta, problem = folder.read_summary()
    if meta is None:
        if problem:
            log.warning("%s: %s; the video runs again", folder.summary_path, problem)
        return None
    batch = meta.get("batch")
    if (meta.get("status") != "complete" or meta.get("truncated") is not False
            or not isinstance(batch, dict) or batch.get("config_hash") != chash):
        return None
    if batch.get("name") != video.name or batch.get("source") != video.source:
        log.warning("%s holds the run of %s, not of %s; the video runs again", folder.path,
                    batch.get("source"), video.source)
        return None
    changed = folder.changed(batch.get("files"))
    if changed:
        log.warning("%s: %s since the batch wrote it; the video runs again", folder.path,
                    changed)
        return None
    return meta


def read_index(path: Path) -> dict[str, dict[str, str]]:
    """The rows of an index file by name (empty when there is none or it cannot be read)."""
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            return {r["name"]: r for r in csv.DictReader(fh) if r.get("name")}
    except (OSError, ValueError, KeyError):
        return {}


def write_index(rows: Sequence[Mapping[str, Any]], path: Path) -> None:
    """Write ``rows`` to ``path`` (CSV) and beside it to ``index.parquet`` (with ``pyarrow``),
    each atomically. A Parquet copy that cannot be written (a full disk, no ``pyarrow``) is
    removed, so that the one beside the CSV is never an older index."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=INDEX_COLUMNS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: r.get(k, "") for k in INDEX_COLUMNS})
    atomic_write_text(path, buf.getvalue())
    parquet = path.with_suffix(".parquet")
    try:
        import pyarrow  # noqa: F401 - the Parquet copy is optional
    except ImportError:
        parquet.unlink(missing_ok=True)
        return
    try:
        atomic_write_bytes(parquet, _parquet(rows))
    except (OSError, DiskFullError) as exc:
        parquet.unlink(missing_ok=True)
        log.warning("%s not written (%s): removed, %s holds the index", parquet.name,
                    printable(exc), path.name)


_INTS = ("frames", "tracks", "attempts")
_FLOATS = ("fps", "wall_s", *METRICS)


def _parquet(rows: Sequence[Mapping[str, Any]]) -> bytes:
    """The index rows as Parquet: counts as int64, rates and metrics as float64, the rest as
    strings; an empty cell is null."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    def cell(k: str, v: Any) -> Any:
        if v is None or v == "":
            return None
        if k in _INTS:
            return int(float(v))
        return float(v) if k in _FLOATS else str(v)

    types = {k: pa.int64() if k in _INTS else pa.float64() if k in _FLOATS else pa.string()
             for k in INDEX_COLUMNS}
    table = pa.table({k: pa.array([cell(k, r.get(k)) for r in rows], type=types[k])
                      for k in INDEX_COLUMNS})
    sink = io.BytesIO()
    pq.write_table(table, sink)
    return sink.getvalue()


def _check_names(videos: Sequence[Video]) -> None:
    reserved = {f.casefold() for f in BATCH_FILES}
    for v in videos:
        if (not v.name or v.name.startswith(".") or any(c in v.name for c in "/\\")
                or not v.name.isprintable()):
            raise ConfigError(f"video name {v.name!r}: a results folder name must not start "
                              "with '.' nor hold slashes or control characters")
        if v.name.casefold() in reserved:
            raise ConfigError(f"video name {v.name!r} is the name of a file the batch writes in "
                              f"RESULTS ({', '.join(BATCH_FILES)}): name the video otherwise")


def run_batch(sources: str | Sequence[str], results: str | Path,
              config: PipelineConfig | str | Path | None = None, *, jobs: int = 1,
              cluster: str | None = None, client: Any = None, resume: bool = False,
              retries: int = 2, timeout_s: float | None = 3600, scene: str | None = None,
              camera: str | None = None, gt_from: str | None = None,
              progress: Callable[[Mapping[str, float]], None] | None = None
              ) -> list[dict[str, Any]]:
    """Track every video of ``sources`` into ``results`` and return the index rows.

    ``sources`` is one SOURCE or a list of them (files, folders, globs, manifest ``.toml``
    files, ``synth:`` scenes: :func:`~motiontrack.batch.sources.expand_sources`); ``config`` a
    :class:`~motiontrack.config.PipelineConfig`, the path of a TOML config, or None for the
    defaults. Runs on ``client`` (a ``distributed.Client``, left open) when given, else on the
    scheduler at ``cluster``, else on a local cluster of ``jobs`` worker processes. ``scene``
    and ``camera`` files apply to every video without its own (from a manifest); ``gt_from`` is
    a manifest giving videos their ground truth (:func:`~motiontrack.batch.sources.with_files`).
    With ``resume``, videos whose folder holds a complete run of theirs with this config, its
    outputs as committed, keep it (and their index row). A video still running after
    ``timeout_s`` seconds (None: no limit) stops and is a ``timeout`` row. ``progress`` is
    called with counts ``done``, ``failed`` (timeouts and truncated videos included),
    ``running``, ``total``, the ``frames`` tracked so far and the cluster's ``fps`` (over the
    last few seconds) whenever a video finishes and as workers report frames (every
    :data:`REPORT_EVERY_S` seconds). Interrupted (``KeyboardInterrupt``), the batch cancels its
    tasks and writes the videos not finished as ``interrupted`` rows before the interruption
    propagates.
    """
    _check_limits(timeout_s=timeout_s, retries=retries, jobs=jobs)
    cfg = _config_of(config)
    specs = [sources] if isinstance(sources, (str, Path)) else list(sources)
    videos = with_files(expand_sources(specs), scene=scene, camera=camera, gt_from=gt_from)
    _check_names(videos)
    out = Path(results)
    out.mkdir(parents=True, exist_ok=True)
    chash = config_hash(cfg)
    with OutputLock(out):
        remove_folder_temps(out)   # of the index files of a killed batch
        index = _Index(out, videos, _resumed_rows(out, videos, chash) if resume else {},
                       progress)
        index.save()
        batch_id = f"motiontrack-batch-{uuid.uuid4().hex[:12]}"
        topic = batch_id if progress is not None else None
        tasks = [BatchTask(v, str(out.resolve()), to_dict(cfg), chash, timeout_s, topic,
                           f"{batch_id}-stop") for v in videos if v.name not in index.rows]
        if tasks:
            manager = dask_client(jobs, cluster) if client is None else _given(client)
            _run_tasks(manager, tasks, index, retries=retries, timeout_s=timeout_s)
        return _finish(out, [index.rows[v.name] for v in videos])


def _check_limits(*, timeout_s: float | None, retries: int, jobs: int) -> None:
    """:class:`ConfigError` for a batch option out of its range."""
    if timeout_s is not None and not timeout_s > 0:
        raise ConfigError(f"--timeout-s must be > 0, got {timeout_s}")
    if retries < 0:
        raise ConfigError(f"--retries must be >= 0, got {retries}")
    if jobs < 1:
        raise ConfigError(f"-j must be >= 1, got {jobs}")


def _config_of(config: PipelineConfig | str | Path | None) -> PipelineConfig:
    """The config a batch runs with: ``config`` itself, the TOML file it names, or the
    defaults."""
    if config is None:
        return PipelineConfig()
    return config if isinstance(config, PipelineConfig) else load_config(config)


def _resumed_rows(out: Path, videos: Sequence[Video], chash: str) -> dict[str, dict[str, Any]]:
    """The index rows, by name, of the videos whose folder holds a complete run made with the
    config ``chash``: the row of the old index, or a ``done`` row when it has none."""
    old = read_index(out / INDEX_FILE)
    rows = {}
    for v in videos:
        meta = _complete(out, v, chash)
        if meta is not None:
            rows[v.name] = _kept_row(v, meta, old.get(v.name), chash)
    log.info("resuming: %d of %d videos are done", len(rows), len(videos))
    return rows


def _kept_row(video: Video, meta: Mapping[str, Any], old: Mapping[str, str] | None,
              chash: str) -> dict[str, Any]:
    """The index row of a video ``--resume`` keeps: its row of the old index when that row is
    of this run (same source, config, frames and tracks), else one made from its summary."""
    same = (old is not None and old.get("status") == "done" and old.get("source") == video.source
            and old.get("config_hash") == chash
            and old.get("frames") == str(meta.get("frames"))
            and old.get("tracks") == str(meta.get("tracks")))
    if same:
        return dict(old)
    acc = meta.get("accuracy") if isinstance(meta.get("accuracy"), dict) else {}
    return {"name": video.name, "source": video.source, "status": "done",
            "config_hash": chash, "frames": meta.get("frames", ""),
            "fps": meta.get("fps", ""), "tracks": meta.get("tracks", ""),
            **{k: acc[k] for k in METRICS if k in acc}}


class _Index:
    """The rows of a batch by name as its videos finish, ``index.csv`` rewritten after each,
    and the counts its ``progress`` callback is given. Finished videos and the workers' frame
    reports arrive on two threads: one lock guards both."""

    def __init__(self, out: Path, videos: Sequence[Video], rows: Mapping[str, dict[str, Any]],
                 progress: Callable[[Mapping[str, float]], None] | None) -> None:
        self.path = out / INDEX_FILE
        self.order = {v.name: i for i, v in enumerate(videos)}
        self.rows = dict(rows)
        self.counts = {"done": len(rows), "failed": 0, "running": 0, "total": len(videos)}
        self.progress = progress
        self.rate = _Rate()
        self.lock = threading.Lock()
        self.workers = 1

    def save(self) -> None:
        write_index(sorted(self.rows.values(), key=lambda r: self.order[r["name"]]), self.path)

    def report(self) -> None:
        if self.progress is not None:
            self.progress({**self.counts, "frames": self.rate.total(), "fps": self.rate.fps()})

    def started(self, workers: int, tasks: int) -> None:
        """The cluster is up with ``workers`` threads for ``tasks`` videos."""
        self.workers = workers
        self.counts["running"] = min(tasks, workers)
        self.report()

    def finished(self, i: int, row: dict[str, Any], attempts: int) -> None:
        """A video's row (``map_tasks``' ``on_result``)."""
        row["attempts"] = attempts
        with self.lock:
            self.rows[row["name"]] = row
            self.counts["done" if row["status"] == "done" else "failed"] += 1
            left = self.counts["total"] - self.counts["done"] - self.counts["failed"]
            self.counts["running"] = min(left, self.workers)
            self.rate.seen(row["name"], int(row.get("frames") or 0))
            self.save()
            self.report()

    def reported(self, event: tuple[float, Any]) -> None:
        """A worker's report of a running video's frames (a Dask topic's handler)."""
        msg = event[1]
        with self.lock:
            if isinstance(msg, dict) and msg.get("name") not in self.rows:
                self.rate.seen(str(msg.get("name")), int(msg.get("frames", 0)))
                self.report()

    def interrupted(self, tasks: Sequence[BatchTask]) -> list[BatchTask]:
        """Write the videos of ``tasks`` not finished as ``interrupted`` rows; those tasks."""
        with self.lock:
            stopped = [t for t in tasks if t.video.name not in self.rows]
            for t in stopped:
                self.rows[t.video.name] = _interrupted_row(t)
            self.save()
        return stopped


def _run_tasks(manager: Any, tasks: Sequence[BatchTask], index: _Index, *, retries: int,
               timeout_s: float | None) -> None:
    """Run ``tasks`` on the cluster ``manager`` opens, each row into ``index`` as it comes.
    Interrupted, the running videos are asked to stop and the unfinished ones written as
    ``interrupted`` rows before the interruption propagates."""
    topic, stop_event = tasks[0].progress_topic, tasks[0].stop_event
    stopped: list[BatchTask] = []
    try:
        with manager as cl:
            index.started(max(1, sum(w.get("nthreads", 1)
                                     for w in cl.scheduler_info()["workers"].values())),
                          len(tasks))
            if topic is not None:
                cl.subscribe_topic(topic, index.reported)
            try:
                map_tasks(cl, run_video, tasks, retries=retries, on_result=index.finished,
                          on_lost=lambda i, exc, n: _lost_row(tasks[i], exc, n),
                          key="motiontrack-batch",
                          hard_timeout_s=None if timeout_s is None
                          else timeout_s + max(10.0, timeout_s / 10),
                          on_timeout=lambda i, n: _hung_row(tasks[i], n))
            except KeyboardInterrupt:
                _ask_to_stop(cl, stop_event)
                stopped = index.interrupted(tasks)
                raise
            finally:
                if topic is not None:
                    cl.unsubscribe_topic(topic)
    finally:
        # a local cluster's workers are gone now, and a partial folder one of them wrote
        # into after the first removal goes too (a remote worker removes its own)
        for t in stopped:
            RunFolder(Path(t.results) / t.video.name).partial().remove()


def _finish(out: Path, rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The final rows, after writing the combined metrics of the videos with ground truth and
    the event counts of those with a scene."""
    write_combined(out, rows)
    write_counts(out, rows)
    write_event_store(out, rows)
    return rows


class _given:
    """A caller's client as a context manager that leaves it open."""

    def __init__(self, client: Any) -> None:
        self.client = client

    def __enter__(self) -> Any:
        return self.client

    def __exit__(self, *exc: Any) -> None:
        return None
