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
import shutil
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

from .. import __version__
from ..config import PipelineConfig, apply_overrides, from_dict, to_dict
from ..errors import ConfigError, printable
from ..io.atomic import OutputLock, atomic_write_bytes, atomic_write_text
from ..run.executor import dask_client, map_tasks
from .combined import write_combined
from .sources import Video, expand_sources

log = logging.getLogger(__name__)

__all__ = ["INDEX_FILE", "INDEX_COLUMNS", "BatchTask", "run_video", "run_batch", "config_hash"]

INDEX_FILE = "index.csv"
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


class VideoTimeout(Exception):
    """A video ran longer than the batch's ``--timeout-s``."""


def _worker_name() -> str:
    try:
        from distributed import get_worker

        return str(get_worker().name)
    except (ImportError, ValueError):   # not on a Dask worker
        return "local"


def _one_line(exc: BaseException) -> str:
    text = printable(exc).splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".strip()


def run_video(task: BatchTask, attempt: int = 1) -> dict[str, Any]:
    """Run one video into ``RESULTS/<name>`` and return its index row; every error becomes a
    ``failed`` row (its partial folder removed), only an interruption propagates."""
    import cv2

    from ..io.annotations import read_annotations
    from ..run.jobs import track_job

    v = task.video
    out = Path(task.results)
    partial, final = out / f".{v.name}.partial", out / v.name
    t0 = time.perf_counter()
    row: dict[str, Any] = {"name": v.name, "source": v.source, "status": "failed", "error": "",
                           "worker": _worker_name(), "attempts": attempt,
                           "config_hash": task.config_hash, "motiontrack_version": __version__,
                           "opencv_version": cv2.__version__}
    try:
        shutil.rmtree(partial, ignore_errors=True)   # of a killed attempt
        overrides = [f"measure.camera={json.dumps(v.camera)}"] if v.camera else []
        cfg = apply_overrides(from_dict(PipelineConfig, dict(task.config)), overrides)
        gt = read_annotations(v.gt, mot_kind="gt") if v.gt else None
        job = track_job(v.source, cfg, partial, force=True, gt=gt, scene=v.scene)
        deadline = None if task.timeout_s is None else t0 + task.timeout_s
        late: list[bool] = []

        def over_time() -> bool:
            if time.perf_counter() > deadline:
                late.append(True)
            return bool(late)

        # polled after each frame: the run stops itself, so its worker is free at once
        try:
            summary = job.run(should_stop=None if deadline is None else over_time)
        except KeyboardInterrupt:
            if not late:
                raise
            raise VideoTimeout(f"ran longer than --timeout-s {task.timeout_s:g}") from None
        meta = json.loads((partial / "summary.json").read_text(encoding="utf-8"))
        # the paths the summary names are those of the finished folder
        meta["outputs"] = {k: str(final / Path(p).name) for k, p in meta.get("outputs", {}).items()}
        meta["batch"] = {"name": v.name, "config_hash": task.config_hash}
        atomic_write_text(partial / "summary.json", json.dumps(meta, indent=2) + "\n")
        if final.exists():   # a redone video: the old folder goes as the new one arrives
            old = out / f".{v.name}.old"
            shutil.rmtree(old, ignore_errors=True)
            final.rename(old)
            partial.rename(final)
            shutil.rmtree(old, ignore_errors=True)
        else:
            partial.rename(final)
        row.update(status="done", frames=summary.frames, fps=round(summary.fps, 3),
                   tracks=summary.tracks)
        row.update({k: summary.accuracy[k] for k in METRICS if k in (summary.accuracy or {})})
    except Exception as exc:   # noqa: BLE001 - one bad video never stops the batch
        shutil.rmtree(partial, ignore_errors=True)
        if isinstance(exc, VideoTimeout):
            row["status"] = "timeout"
        row["error"] = _one_line(exc)
        log.warning("%s %s: %s", v.name, row["status"], row["error"])
    row["wall_s"] = round(time.perf_counter() - t0, 3)
    return row


def _lost_row(task: BatchTask, exc: BaseException, attempts: int) -> dict[str, Any]:
    """The ``failed`` row of a video whose worker died on every attempt."""
    import cv2

    v = task.video
    shutil.rmtree(Path(task.results) / f".{v.name}.partial", ignore_errors=True)
    return {"name": v.name, "source": v.source, "status": "failed",
            "error": f"its worker died on each of {attempts} attempts ({_one_line(exc)})",
            "attempts": attempts, "config_hash": task.config_hash,
            "motiontrack_version": __version__, "opencv_version": cv2.__version__}


def _hung_row(task: BatchTask, attempts: int) -> dict[str, Any]:
    """The ``timeout`` row of a video whose run did not stop itself (stuck inside a frame), so
    that its worker was restarted."""
    row = _lost_row(task, TimeoutError(), attempts)
    row.update(status="timeout", error=f"VideoTimeout: ran longer than --timeout-s "
                                         f"{task.timeout_s:g} and did not stop; worker restarted")
    return row


def _complete(results: Path, name: str, chash: str) -> bool:
    """Whether ``RESULTS/<name>`` holds a complete run made with the config ``chash``."""
    try:
        meta = json.loads((results / name / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return (isinstance(meta, dict) and meta.get("status") == "complete"
            and isinstance(meta.get("batch"), dict) and meta["batch"].get("config_hash") == chash)


def read_index(path: Path) -> dict[str, dict[str, str]]:
    """The rows of an index file by name (empty when there is none or it cannot be read)."""
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            return {r["name"]: r for r in csv.DictReader(fh) if r.get("name")}
    except (OSError, ValueError, KeyError):
        return {}


def write_index(rows: Sequence[Mapping[str, Any]], path: Path) -> None:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=INDEX_COLUMNS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: r.get(k, "") for k in INDEX_COLUMNS})
    atomic_write_text(path, buf.getvalue())
    try:
        import pyarrow  # noqa: F401 - the Parquet copy is optional
    except ImportError:
        return
    atomic_write_bytes(path.with_suffix(".parquet"), _parquet(rows))


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
    for v in videos:
        if (not v.name or v.name.startswith(".") or any(c in v.name for c in "/\\")
                or not v.name.isprintable()):
            raise ConfigError(f"video name {v.name!r}: a results folder name must not start "
                              "with '.' nor hold slashes or control characters")


def run_batch(sources: Sequence[str], results: str | Path, config: PipelineConfig | None = None,
              *, jobs: int = 1, cluster: str | None = None, client: Any = None,
              resume: bool = False, retries: int = 2, timeout_s: float | None = 3600,
              progress: Callable[[Mapping[str, int]], None] | None = None) -> list[dict[str, Any]]:
    """Track every video of ``sources`` into ``results`` and return the index rows.

    Runs on ``client`` when given, else on the scheduler at ``cluster``, else on a local
    cluster of ``jobs`` worker processes. With ``resume``, videos whose folder holds a complete
    run with this config keep it (and their index row). A video still running after
    ``timeout_s`` seconds (None: no limit) stops and is a ``timeout`` row. ``progress`` is called
    with counts ``done``, ``failed`` (timeouts included), ``running``, ``total`` whenever a video
    finishes.
    """
    if timeout_s is not None and not timeout_s > 0:
        raise ConfigError(f"--timeout-s must be > 0, got {timeout_s}")
    if retries < 0:
        raise ConfigError(f"--retries must be >= 0, got {retries}")
    if jobs < 1:
        raise ConfigError(f"-j must be >= 1, got {jobs}")
    cfg = config if config is not None else PipelineConfig()
    videos = expand_sources(sources)
    _check_names(videos)
    out = Path(results)
    out.mkdir(parents=True, exist_ok=True)
    chash = config_hash(cfg)
    with OutputLock(out):
        old = read_index(out / INDEX_FILE)
        rows: dict[str, dict[str, Any]] = {}
        if resume:
            for v in videos:
                if _complete(out, v.name, chash):
                    rows[v.name] = dict(old.get(v.name) or {"name": v.name, "source": v.source,
                                                             "status": "done",
                                                             "config_hash": chash})
            log.info("resuming: %d of %d videos are done", len(rows), len(videos))
        todo = [v for v in videos if v.name not in rows]
        order = {v.name: i for i, v in enumerate(videos)}
        counts = {"done": len(rows), "failed": 0,
                  "running": 0, "total": len(videos)}

        def save() -> None:
            write_index(sorted(rows.values(), key=lambda r: order[r["name"]]), out / INDEX_FILE)

        def finished(i: int, row: dict[str, Any], attempts: int) -> None:
            row["attempts"] = attempts
            rows[row["name"]] = row
            counts["done" if row["status"] == "done" else "failed"] += 1
            left = len(videos) - counts["done"] - counts["failed"]
            counts["running"] = min(left, workers)
            save()
            if progress is not None:
                progress(dict(counts))

        save()
        tasks = [BatchTask(v, str(out.resolve()), to_dict(cfg), chash, timeout_s) for v in todo]
        if not tasks:
            return _finish(out, [rows[v.name] for v in videos])
        manager = dask_client(jobs, cluster) if client is None else _given(client)
        with manager as cl:
            workers = max(1, sum(w.get("nthreads", 1)
                                 for w in cl.scheduler_info()["workers"].values()))
            counts["running"] = min(len(tasks), workers)
            if progress is not None:
                progress(dict(counts))
            map_tasks(cl, run_video, tasks, retries=retries, on_result=finished,
                      on_lost=lambda i, exc, n: _lost_row(tasks[i], exc, n),
                      key="motiontrack-batch",
                      hard_timeout_s=None if timeout_s is None
                      else timeout_s + max(10.0, timeout_s / 10),
                      on_timeout=lambda i, n: _hung_row(tasks[i], n))
        return _finish(out, [rows[v.name] for v in videos])


def _finish(out: Path, rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The final rows, after writing the combined metrics of the videos with ground truth."""
    write_combined(out, rows)
    return rows


class _given:
    """A caller's client as a context manager that leaves it open."""

    def __init__(self, client: Any) -> None:
        self.client = client

    def __enter__(self) -> Any:
        return self.client

    def __exit__(self, *exc: Any) -> None:
        return None
