"""Parameter studies: run the pipeline once per point of a parameter grid and score every run.

This reproduces the thesis' evaluation workflow (its ``mkdaevaluation`` scripts, §4.4): each run is
one point of the grid applied to a base configuration, on one or more sequences; the motion
detector's regions (the *detections*) are scored with the framewise metrics of §4.1
(:func:`~motiontrack.evaluate.framewise.evaluate_framewise`: pixel, object-area and localized
object precision/recall) and the confirmed tracks with the same framewise metrics plus
CLEAR-MOT / Identity / HOTA (:func:`~motiontrack.evaluate.mot.evaluate_tracking`, zero-marked
ground truth counted as the study's ``scoring`` names, :mod:`motiontrack.evaluate.scoring`).

Grid syntax (one ``--param`` per parameter, the grid is their Cartesian product; parsed by
:func:`~motiontrack.studies.params.parse_param`)::

    motion.median.threshold=0.05,0.1,0.2      explicit values (TOML literals or bare strings)
    regions.min_size=0:0.004:0.001            a:b:step, both ends inclusive

The result is a tidy table: one row per run × sequence with the run number, the sequence, its
group, every grid parameter (column named by its key) and every metric
(``det_<framewise key>`` for regions, ``trk_<framewise key>`` for tracks, and the tracking metrics
``HOTA``, ``MOTA``, ``IDF1``...). Rows come back in grid order whichever executor ran them (serial,
a process pool, or a Dask cluster), so the tables are byte-identical.

Every study writes ``study.json`` (sources, ground truth, grid, base config, evaluation parameters,
versions); :func:`load_study` + :func:`run_sweep` reproduce it (``motiontrack sweep --replay DIR``).
Every finished run leaves its table row next to its files (``runs/rNNN/<sequence>/row.json``), so
a sweep stopped part-way continues where it stopped (``run_sweep(..., resume=True)``,
``motiontrack sweep ... --resume``). A study has at most :data:`MAX_RUNS` runs × sequences.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import json
import logging
import math
import os
import platform
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

import cv2
import numpy as np

from ..config import PipelineConfig, apply_overrides, from_dict, save_config, to_dict
from ..config_activity import check_study_keys
from ..errors import ConfigError, InputError, printable
from ..evaluate.framewise import evaluate_framewise
from ..evaluate.mot import evaluate_tracking
from ..evaluate.score import scored_frames
from ..evaluate.scoring import DEFAULT_SCORING, ignores_zero_marked
from ..io.annotations import read_ground_truth
from ..io.atomic import (DiskFullError, OutputLock, atomic_write_text, check_writable,
                         remove_leftover_temps, remove_outputs)
from ..io.manifest import SequenceSpec, absolute_path, default_sequence_name, read_manifest
from ..io.mot import read_mot
from ..pipeline import completes_tracks, fill_gap_frames, open_configured_source
from ..run.executor import dask_client, map_tasks
from ..run.job import Job
from ..run.pool import pool_map
from ..run.processors import TrackProcessor
from ..run.writers import IntermediateWriter, RegionsWriter, TracksWriter
from ..synth import parse_synth_spec
from ..version import __version__
from .params import format_value, parse_param
from .plots import study_figures
from .study_file import (STUDY_FILE, read_study_meta, settings_differences, settings_key,
                         study_meta_problem)
from .table import summarise_runs, write_table

log = logging.getLogger(__name__)

__all__ = [
    "Study", "RunSpec", "SweepResult", "execute_run", "execute", "run_sweep", "load_study",
    "study_from_args", "check_ground_truth", "versions", "study_key", "TABLE_FILE",
    "SUMMARY_FILE", "RUN_RECORD_FILE", "MAX_RUNS", "FRAMEWISE_PAIRS", "TRACKING_KEYS",
]

TABLE_FILE = "results.csv"
SUMMARY_FILE = "summary.csv"
STUDY_FORMAT = 1

#: per run × sequence, next to its tracks and regions: the table row and the files' digests,
#: written last, so that ``--resume`` knows the run finished
RUN_RECORD_FILE = "row.json"
#: the files of a run that ``--resume`` checks against the digests of its record
RUN_FILES = ("tracks.txt", "regions.txt")

#: most runs × sequences a study may have: a larger grid is refused before anything is written
MAX_RUNS = 100_000

#: the three precision–recall pairs of the thesis' figure 4.4: label → (precision key, recall key)
FRAMEWISE_PAIRS: dict[str, tuple[str, str]] = {
    "pixel": ("pixel_precision", "pixel_recall"),
    "object": ("object_area_precision", "object_area_recall"),
    "localized object": ("localized_object_precision", "localized_object_recall"),
}

#: the tracking metrics copied into the table (from evaluate_tracking's flat dict)
TRACKING_KEYS = ("HOTA", "DetA", "AssA", "LocA", "MOTA", "MOTP", "IDF1", "IDP", "IDR", "IDSW",
                 "TP", "FP", "FN", "MT", "ML", "Frag")

#: intermediate streams a run may save (see motiontrack.intermediate)
SAVE_STREAMS = ("background", "difference", "motion", "annotated")


# ------------------------------------------------------------------------------- the study
@dataclass(frozen=True)
class RunSpec:
    """Everything one worker needs for one run × sequence (picklable, self-contained)."""

    run: int
    params: tuple[tuple[str, Any], ...]
    sequence: SequenceSpec
    base_config: Mapping[str, Any] = field(repr=False)
    xi: float = 0.75
    save: tuple[str, ...] = ()
    out_dir: str | None = None
    scoring: str = DEFAULT_SCORING

    def overrides(self) -> list[str]:
        return [f"{k}={format_value(v)}" for k, v in self.params]

    def run_dir(self) -> str:
        return f"runs/r{self.run:03d}/{self.sequence.name}"


@dataclass(frozen=True)
class Study:
    """A parameter study: sequences × the Cartesian product of ``grid`` applied to ``base_config``.

    Parameters
    ----------
    sequences : tuple of SequenceSpec
    grid : tuple of (key, values)
        In ``--param`` order; the first parameter varies slowest.
    base_config : dict
        The resolved base :class:`~motiontrack.config.PipelineConfig` as a nested dict.
    xi : float
        Localization threshold of the localized object metrics (thesis: 0.75).
    save : tuple of str
        Intermediate streams written per run (``background``, ``difference``, ``motion``,
        ``annotated``).
    scoring : str
        How zero-marked ground truth counts in the tracking metrics
        (:data:`~motiontrack.evaluate.scoring.SCORING`).
    """

    sequences: tuple[SequenceSpec, ...]
    grid: tuple[tuple[str, tuple[Any, ...]], ...]
    base_config: Mapping[str, Any] = field(repr=False)
    xi: float = 0.75
    save: tuple[str, ...] = ()
    scoring: str = DEFAULT_SCORING

    def __post_init__(self) -> None:
        if not self.sequences:
            raise ConfigError("a study needs at least one sequence")
        if not self.grid:
            raise ConfigError("a study needs at least one --param")
        for key, values in self.grid:
            if not isinstance(key, str) or not all(p.isidentifier() for p in key.split(".")):
                raise ConfigError(f"--param key must be a dotted config key, got {key!r}")
            if not values or not all(isinstance(v, (bool, int, float, str)) for v in values):
                raise ConfigError(f"--param {key}: needs one or more numbers, booleans or strings, "
                                  f"got {list(values)!r}")
        # the bound comes before anything that walks the grid (a 10^8-point grid would hang)
        if self.n_runs > MAX_RUNS:
            n_points = math.prod(len(v) for _, v in self.grid)
            raise ConfigError(
                f"the grid has {n_points} points x {len(self.sequences)} sequence(s) = "
                f"{self.n_runs} runs, more than the bound of {MAX_RUNS}; give fewer --param values")
        keys = [k for k, _ in self.grid]
        if len(set(keys)) != len(keys):
            raise ConfigError(f"--param keys must be distinct, got {keys}")
        if not (0.0 <= float(self.xi) <= 1.0):
            raise ConfigError(f"xi must be in [0, 1], got {self.xi}")
        ignores_zero_marked(self.scoring)
        bad = sorted(set(self.save) - set(SAVE_STREAMS))
        if bad:
            raise ConfigError(f"unknown --save stream(s) {', '.join(bad)}; valid: {', '.join(SAVE_STREAMS)}")
        names = [s.name for s in self.sequences]
        if len(set(names)) != len(names):
            raise ConfigError(f"sequence names must be unique, got {names}")
        # every grid point must give a valid config: fail before any run starts
        base = from_dict(PipelineConfig, dict(self.base_config))
        for key, values in self.grid:
            for v in values:
                apply_overrides(base, [f"{key}={format_value(v)}"])

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(k for k, _ in self.grid)

    @property
    def n_runs(self) -> int:
        """Runs × sequences, without walking the grid."""
        return math.prod(len(v) for _, v in self.grid) * len(self.sequences)

    def points(self) -> list[tuple[tuple[str, Any], ...]]:
        """Grid points in order (first parameter slowest)."""
        return [tuple(zip(self.keys, combo)) for combo in itertools.product(*(v for _, v in self.grid))]

    def specs(self, out_dir: str | Path | None = None) -> list[RunSpec]:
        """One :class:`RunSpec` per grid point × sequence (run numbers start at 1)."""
        od = str(Path(out_dir).resolve()) if out_dir is not None else None
        return [RunSpec(run=i, params=pt, sequence=seq, base_config=self.base_config, xi=self.xi,
                        save=self.save, out_dir=od, scoring=self.scoring)
                for i, pt in enumerate(self.points(), 1) for seq in self.sequences]

    def as_dict(self) -> dict[str, Any]:
        return {
            "format": STUDY_FORMAT,
            "sequences": [s.as_dict() for s in self.sequences],
            "grid": [{"key": k, "values": list(v)} for k, v in self.grid],
            "base_config": self.base_config,
            "evaluation": {"xi": self.xi, "scoring": self.scoring,
                           "detections": "motion regions (framewise, thesis §4.1)",
                           "tracks": "confirmed tracks (framewise + CLEAR-MOT/Identity/HOTA, IoU 0.5)"},
            "save": list(self.save),
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "Study":
        """The study of a ``study.json`` object; :class:`InputError` for a wrong JSON shape,
        :class:`ConfigError` for settings out of range."""
        problem = study_meta_problem(d)
        if problem:
            raise InputError(f"malformed study meta data: {problem}")
        if d.get("format") != STUDY_FORMAT:
            raise InputError(f"unsupported study format {d.get('format')!r} (expected {STUDY_FORMAT})")
        return cls(
            sequences=tuple(SequenceSpec(**s) for s in d["sequences"]),
            grid=tuple((g["key"], tuple(g["values"])) for g in d["grid"]),
            base_config=d["base_config"],
            xi=float(d["evaluation"]["xi"]),
            save=tuple(d.get("save", ())),
            # a study.json without "scoring" had its tracks scored with ignore regions
            scoring=d["evaluation"].get("scoring", "ignore-regions"),
        )


def versions() -> dict[str, str]:
    """Versions that can change the numbers of a study."""
    return {"motiontrack": __version__, "python": platform.python_version(), "numpy": np.__version__,
            "opencv": cv2.__version__, "platform": platform.platform()}


def load_study(folder: str | Path) -> tuple[Study, dict[str, Any]]:
    """Read ``study.json`` of a study folder: the :class:`Study` and the full meta dict."""
    meta = read_study_meta(folder)
    try:
        return Study.from_dict(meta), meta
    except (InputError, ConfigError) as exc:  # an unknown format, settings out of range
        raise InputError(f"{printable(Path(folder) / STUDY_FILE)}: {printable(exc)}") from None


# ------------------------------------------------------------------------------- one run
def _load_gt(seq: SequenceSpec):
    if seq.gt is None:
        return parse_synth_spec(seq.source).ground_truth()
    return read_ground_truth(seq.gt)


def execute_run(spec: RunSpec, should_stop: Callable[[], bool] | None = None) -> dict[str, Any]:
    """Run the pipeline for one run × sequence and score it (pure apart from optional
    intermediate videos written under ``spec.out_dir``).

    ``should_stop`` is polled after each frame: once it says stop, the run ends there and
    ``KeyboardInterrupt`` is raised (the run is not finished, nothing of it is returned).

    The run is a :class:`~motiontrack.run.job.Job` writing its tracks (as ``motiontrack track``
    writes them) and its regions to a temporary folder of the worker; they are scored from there.

    Returns
    -------
    dict
        ``{"row": {...table row...}, "files": {relative path: text}}`` where files are the run's
        ``tracks.txt`` and ``regions.txt`` (MOTChallenge CSV, 1-based frames) for the caller to
        write, so that remote workers need no shared file system.
    """
    cfg = apply_overrides(from_dict(PipelineConfig, dict(spec.base_config)), spec.overrides())
    seq = spec.sequence
    gt = _load_gt(seq)
    with tempfile.TemporaryDirectory(prefix="motiontrack-run-") as tmp:
        job = _run_job(spec, cfg, Path(tmp))
        summary = job.run(should_stop=should_stop)
        tracks = read_mot(job.paths["tracks"], kind="results")
        regions = read_mot(job.paths["regions"], kind="results")
        files = {f"{spec.run_dir()}/{name}.txt": job.paths[name].read_text(encoding="utf-8")
                 for name in ("tracks", "regions")}
    info = job.info
    first = job.source.start + 1
    n_tracks = int(len(np.unique(tracks.ids))) if len(tracks) else 0
    # the processed frames the ground truth covers, as `motiontrack track --gt` scores them
    gt, tracks, window = scored_frames(gt, tracks, (first, first + summary.frames - 1))
    lo, hi = window.first, window.last
    size = (float(info.width), float(info.height))
    row: dict[str, Any] = {"run": spec.run, "sequence": seq.name, "group": seq.group}
    row.update({k: v for k, v in spec.params})
    row["frames"] = summary.frames
    row["n_tracks"] = n_tracks
    det = evaluate_framewise(gt, regions, spec.xi, frame_size=size, frames=(lo, hi))[0]
    trk = evaluate_framewise(gt, tracks, spec.xi, frame_size=size, frames=(lo, hi))[0]
    for prefix, res in (("det_", det), ("trk_", trk)):
        row.update({prefix + k: float(v) for k, v in res.items()})
        for label, (pk, rk) in FRAMEWISE_PAIRS.items():
            row[f"{prefix}{label.replace(' ', '_')}_f1"] = _f1(res[pk], res[rk])
    # zero-marked rows count as `motiontrack track --gt --scoring` counts them
    mot = evaluate_tracking(gt, tracks, ignore_zero_marked=ignores_zero_marked(spec.scoring))
    row.update({k: float(mot[k]) for k in TRACKING_KEYS if k in mot})
    return {"row": row, "files": files}


def _run_job(spec: RunSpec, cfg: PipelineConfig, tmp: Path) -> Job:
    """The job of one run: the tracks (completed as ``motiontrack track`` completes them,
    ``tracker.fill_motion``) and the regions, plus the intermediate movies asked for."""
    src = open_configured_source(spec.sequence.source, cfg.source)
    try:
        max_gap = (fill_gap_frames(cfg, src.info.fps, external=False)
                   if completes_tracks(cfg, external=False) else None)
        writers: list = [TracksWriter(tmp, max_gap=max_gap), RegionsWriter(tmp)]
        if spec.save and spec.out_dir:
            writers.append(IntermediateWriter(Path(spec.out_dir) / spec.run_dir(), spec.save,
                                              cfg.output.codec))
        proc = TrackProcessor(cfg, src.info, needs_background="background" in spec.save)
        # no summary.json: the sweep records the run (row.json) when it has scored it
        return Job(src, proc, writers, tmp, force=True, summary=False)
    except BaseException:
        src.close()
        raise


def _f1(p: float, r: float) -> float:
    """Harmonic mean of precision and recall (nan when either is nan, 0 when both are 0)."""
    if math.isnan(p) or math.isnan(r):
        return float("nan")
    return 2 * p * r / (p + r) if p + r > 0 else 0.0


# ------------------------------------------------------------------------------- executors
def _worker_init() -> None:
    """One OpenCV thread per worker process: the runs are the parallelism."""
    cv2.setNumThreads(1)


def _execute_attempt(spec: RunSpec, attempt: int) -> dict[str, Any]:
    """:func:`execute_run` as a task of :func:`~motiontrack.run.executor.map_tasks`."""
    return execute_run(spec)


def execute(specs: Sequence[RunSpec], jobs: int = 1, cluster: str | None = None,
            progress: Callable[[int], None] | None = None,
            on_result: Callable[[int, dict[str, Any]], None] | None = None,
            should_stop: Callable[[], bool] | None = None) -> list[dict[str, Any]]:
    """Execute ``specs`` and return their results **in spec order**.

    Parameters
    ----------
    jobs : int
        1 = serial in this process; N > 1 = a pool of N spawned processes
        (:func:`~motiontrack.run.pool.pool_map`: its workers stop when asked and die with this
        process; as with any spawned pool, a calling *script* must guard its entry point with
        ``if __name__ == "__main__":``).
    cluster : str, optional
        Address of a Dask distributed scheduler (``tcp://host:8786``); needs ``dask[distributed]``
        and workers that can open the sources. Overrides ``jobs``.
    progress : callable, optional
        Called with the number of runs finished (1) each time one finishes.
    on_result : callable, optional
        Called as ``on_result(index, result)`` as soon as each run finishes (in completion order),
        so a caller can save finished runs before an interruption.
    should_stop : callable, optional
        Polled during the runs (serial and pool): once it says stop, the runs in progress end
        after their current frame, no other run starts, and ``KeyboardInterrupt`` is raised
        after every run that finished meanwhile was passed to ``on_result``. On a Dask cluster
        it is not polled (the caller raises ``KeyboardInterrupt``; the runs are cancelled). On
        ``KeyboardInterrupt`` pending runs are cancelled and the interrupt is re-raised.
    """
    if jobs < 1:
        raise ConfigError(f"-j must be >= 1, got {jobs}")
    results: list[dict[str, Any] | None] = [None] * len(specs)
    if not specs:
        return []

    def done(i: int, res: dict[str, Any]) -> None:
        results[i] = res
        if on_result is not None:
            on_result(i, res)
        if progress is not None:
            progress(1)

    if cluster:
        with dask_client(cluster=cluster) as client:   # the executor batch runs on
            map_tasks(client, _execute_attempt, list(specs),
                      on_result=lambda i, res, _attempts: done(i, res), key="motiontrack-sweep")
    elif jobs == 1:
        for i, s in enumerate(specs):
            if should_stop is not None and should_stop():
                raise KeyboardInterrupt
            done(i, execute_run(s, should_stop))
    else:
        pool_map(execute_run, specs, jobs, on_result=done, should_stop=should_stop,
                 init=_worker_init)
    return results  # type: ignore[return-value]


# ------------------------------------------------------------------------------- resuming
def study_key(study: Study) -> str:
    """SHA-256 of the study's settings: a run record made under other settings is not reused."""
    return settings_key(study.as_dict())


def _check_resumable(out: Path, study: Study) -> bool:
    """Whether ``out`` holds ``study`` to resume: False when it holds no study yet;
    :class:`InputError` naming the differences when it holds one with other settings."""
    if not (out / STUDY_FILE).exists():
        log.info("no %s in %s: nothing to resume, starting the study", STUDY_FILE, printable(out))
        return False
    meta = read_study_meta(out)
    diffs = settings_differences(meta, study.as_dict())
    if diffs:
        more = f"; and {len(diffs) - 5} more" if len(diffs) > 5 else ""
        raise InputError(f"cannot resume {printable(out)}: its study has other settings: "
                         f"{'; '.join(diffs[:5])}{more} (resume with the same settings, or start "
                         "over with --force or another -o)")
    now = versions()
    for k, v in meta.get("versions", {}).items():
        if k != "platform" and k in now and now[k] != v:
            log.warning("study was started with %s %s, this is %s: resumed runs may differ from "
                        "the finished ones", printable(k), printable(v), now[k])
    return True


def _run_record(res: Mapping[str, Any], key: str) -> str:
    """The record of a finished run: the study key, its table row (floats written with repr, so
    they read back exactly) and the digests of its files."""
    digests = {Path(rel).name: hashlib.sha256(text.encode("utf-8")).hexdigest()
               for rel, text in res["files"].items()}
    return json.dumps({"study": key, "row": res["row"], "files": digests}, indent=1,
                      default=lambda o: o.item() if isinstance(o, np.generic) else str(o)) + "\n"


def _finished_run(out: Path, spec: RunSpec, key: str) -> dict[str, Any] | None:
    """The result (``{"row": ...}``) of a run finished in ``out`` under the study ``key``, or
    None when its record or one of its files is missing, unreadable or does not match."""
    folder = out / spec.run_dir()
    try:
        rec = json.loads((folder / RUN_RECORD_FILE).read_text(encoding="utf-8"))
        digests = {name: hashlib.sha256((folder / name).read_text(encoding="utf-8")
                                        .encode("utf-8")).hexdigest() for name in RUN_FILES}
    except (OSError, ValueError, RecursionError):  # missing, not UTF-8, not JSON
        return None
    if not isinstance(rec, dict) or rec.get("study") != key or rec.get("files") != digests:
        return None
    row = rec.get("row")
    if (not isinstance(row, dict) or row.get("run") != spec.run
            or row.get("sequence") != spec.sequence.name):
        return None
    return {"row": row}


# ------------------------------------------------------------------------------- the sweep
@dataclass(frozen=True)
class SweepResult:
    rows: list[dict[str, Any]]
    out_dir: Path
    outputs: dict[str, list[str]]


#: the files of a study folder besides runs/ and figures/ (``--force`` removes them first)
STUDY_OUTPUTS = (STUDY_FILE, "config.toml", TABLE_FILE, Path(TABLE_FILE).stem + ".parquet",
                 SUMMARY_FILE, Path(SUMMARY_FILE).stem + ".parquet", "summary.json")


def _owning_folder(sweep: Callable[..., SweepResult]) -> Callable[..., SweepResult]:
    """``sweep(study, out_dir, ...)`` run as the only owner of ``out_dir``
    (:class:`~motiontrack.io.atomic.OutputLock`): a second sweep into the folder is refused at
    once instead of mixing its runs with this one's."""

    @functools.wraps(sweep)
    def owned(study: Study, out_dir: str | Path, *args: Any, **kwargs: Any) -> SweepResult:
        with OutputLock(out_dir):
            return sweep(study, out_dir, *args, **kwargs)

    return owned


@_owning_folder
def run_sweep(study: Study, out_dir: str | Path, *, jobs: int = 1, cluster: str | None = None,
              progress: Callable[[int], None] | None = None, figures: bool = True,
              force: bool = False, resume: bool = False,
              should_stop: Callable[[], bool] | None = None) -> SweepResult:
    """Run ``study`` and write its folder: ``study.json``, ``config.toml`` (base config),
    ``results.csv`` (+ ``.parquet``), ``summary.csv`` (per-run averages over sequences),
    ``summary.json`` (``"status"``, ``"interrupted"``, runs done; when the sweep is stopped or
    the disk fills, the table holds the finished runs),
    ``runs/rNNN/<sequence>/{tracks,regions}.txt`` and ``row.json`` (the run's table row, written
    last) and, with ``figures``, ``figures/*.png|svg``.

    ``should_stop`` (the CLI's SIGINT/SIGTERM handlers) is polled during the runs: once it says
    stop, the runs in progress end after their current frame, every finished run is kept and
    ``KeyboardInterrupt`` is raised (:func:`execute`). A full device
    (:class:`~motiontrack.io.atomic.DiskFullError`) also keeps the finished runs, then is raised.

    One sweep at a time owns the folder (a second one is refused at once). With ``force`` an
    old study in it (:data:`STUDY_OUTPUTS`, ``runs/``, ``figures/``) is removed before anything
    is written, so that old and new runs never mix.

    With ``resume``, a folder that holds this study (same settings,
    :data:`~motiontrack.studies.study_file.SETTINGS`) is
    continued: a run whose ``row.json`` was written under these settings and whose files match
    its digests is not run again, and the table is the one an uninterrupted sweep writes. A
    folder with other settings is refused (:class:`InputError` naming them); one without
    ``study.json`` starts the study.
    """
    if jobs < 1:
        raise ConfigError(f"-j must be >= 1, got {jobs}")
    if resume and force:
        raise ConfigError("--resume continues a study and --force starts it over: give one of them")
    check_ground_truth(study.sequences)  # a replayed study may name files this machine lacks
    out = Path(out_dir)
    resuming = _prepare_folder(study, out, force=force, resume=resume)
    specs = study.specs(out)
    log.info("sweep: %d runs x %d sequences = %d jobs", len(study.points()), len(study.sequences),
             len(specs))
    key = study_key(study)
    finished = _resumed_runs(out, specs, key, progress) if resuming else {}
    finished = _run_remaining(specs, finished, out, key, jobs=jobs, cluster=cluster,
                              progress=progress, should_stop=should_stop)
    rows = [finished[i]["row"] for i in range(len(specs))]
    return SweepResult(rows=rows, out_dir=out, outputs=_write_results(rows, study, out, figures))


def _prepare_folder(study: Study, out: Path, *, force: bool, resume: bool) -> bool:
    """Make ``out`` ready for ``study`` (refusals, ``--force`` removals, leftovers of a killed
    sweep, ``study.json`` and ``config.toml``) and say whether the study is resumed."""
    resuming = resume and _check_resumable(out, study)
    if not resuming:
        check_writable([out / STUDY_FILE, out / TABLE_FILE], force)
    if force:  # the old study goes before the new one appears: old and new runs never mix
        remove_outputs([out / n for n in STUDY_OUTPUTS], folders=[out / "runs", out / "figures"])
    remove_leftover_temps([out / n for n in STUDY_OUTPUTS])  # of a killed sweep
    out.mkdir(parents=True, exist_ok=True)
    if not resuming:  # a resumed study keeps the versions it was started with
        meta = study.as_dict()
        meta["versions"] = versions()
        meta["runs"] = len(study.points())
        atomic_write_text(out / STUDY_FILE, json.dumps(meta, indent=2) + "\n")
    save_config(from_dict(PipelineConfig, dict(study.base_config)), out / "config.toml")
    return resuming


def _resumed_runs(out: Path, specs: Sequence[RunSpec], key: str,
                  progress: Callable[[int], None] | None) -> dict[int, dict[str, Any]]:
    """The results of the runs of ``specs`` finished in ``out`` under the study ``key``, by
    index (counted as progress at once)."""
    finished = {i: res for i, s in enumerate(specs) if (res := _finished_run(out, s, key))}
    log.info("resuming: %d of %d runs were done, %d to run", len(finished), len(specs),
             len(specs) - len(finished))
    if progress is not None and finished:
        progress(len(finished))
    return finished


def _run_remaining(specs: Sequence[RunSpec], finished: Mapping[int, dict[str, Any]], out: Path,
                   key: str, *, jobs: int, cluster: str | None,
                   progress: Callable[[int], None] | None,
                   should_stop: Callable[[], bool] | None = None) -> dict[int, dict[str, Any]]:
    """Run the specs not in ``finished`` and return the results of all specs by index, with
    ``summary.json`` written. Interrupted or on a full device, the table of the finished runs
    and ``summary.json`` are written (as far as the device allows) before the error
    propagates."""
    done = dict(finished)
    todo = [i for i in range(len(specs)) if i not in done]

    def save_run(j: int, res: dict[str, Any]) -> None:
        # each run's files are written as soon as it finishes: an interruption keeps them; the
        # record comes last, so that a record means the files are complete (--resume)
        i = todo[j]
        for rel, text in res["files"].items():
            atomic_write_text(out / rel, text)
        atomic_write_text(out / specs[i].run_dir() / RUN_RECORD_FILE, _run_record(res, key))
        done[i] = res

    try:
        execute([specs[i] for i in todo], jobs=jobs, cluster=cluster, progress=progress,
                on_result=save_run, should_stop=should_stop)
    except KeyboardInterrupt:
        _write_interrupted(out, done, len(specs))
        raise
    except DiskFullError as exc:
        _write_partial(out, done, len(specs), str(exc))
        raise
    _write_status(out, status="complete", runs_done=len(done), runs=len(specs))
    return done


def _write_status(out: Path, *, status: str, runs_done: int, runs: int) -> None:
    """``summary.json``: how the sweep ended (``"complete"``, ``"interrupted"``, ``"disk full
    writing …"``) and how many runs it finished."""
    atomic_write_text(out / "summary.json", json.dumps(
        {"status": status, "interrupted": status == "interrupted", "runs_done": runs_done,
         "runs": runs}, indent=2) + "\n")


def _write_partial(out: Path, done: Mapping[int, dict[str, Any]], runs: int,
                   status: str) -> bool:
    """The table of the runs finished before the sweep ended early, and ``summary.json`` with
    ``status``; whether the table was written (on a full device it may not fit, and the runs'
    records, which ``--resume`` reads, are what counts)."""
    rows = [done[i]["row"] for i in sorted(done)]
    try:
        if rows:
            write_table(rows, out / TABLE_FILE)
        _write_status(out, status=status, runs_done=len(done), runs=runs)
    except DiskFullError as exc:
        log.debug("no table of the finished runs: %s", exc)
        return False
    return bool(rows)


def _write_interrupted(out: Path, done: Mapping[int, dict[str, Any]], runs: int) -> None:
    """The table of the runs finished before an interruption, and ``summary.json`` saying so."""
    table = _write_partial(out, done, runs, "interrupted")
    log.warning("sweep stopped: %d of %d runs finished%s (continue with --resume)",
                len(done), runs, f"; their table is in {printable(out / TABLE_FILE)}" if table else "")


def _write_results(rows: list[dict[str, Any]], study: Study, out: Path,
                   figures: bool) -> dict[str, list[str]]:
    """The table, the per-run summary and, with ``figures`` (and matplotlib), the figures of a
    finished sweep; the paths written by kind."""
    outputs = {"table": write_table(rows, out / TABLE_FILE),
               "summary": write_table(summarise_runs(rows, study.keys), out / SUMMARY_FILE)[:1]}
    if figures:
        try:
            import matplotlib  # noqa: F401  (optional extra: motiontrack[plot])
        except ImportError:
            log.warning("matplotlib is not installed: no figures (pip install 'motiontrack[plot]')")
        else:
            outputs["figures"] = study_figures(rows, study, out / "figures")
    return outputs


def check_ground_truth(sequences: Iterable[SequenceSpec]) -> None:
    """:class:`InputError` for the first sequence whose ground-truth file does not exist, so
    that a study stops before anything is written rather than at its first run."""
    for s in sequences:
        if s.gt is not None and not os.path.isfile(s.gt):
            raise InputError(f"ground truth of sequence {s.name} not found: {printable(s.gt)}")


def study_from_args(sources: Sequence[str], gt: Sequence[str] | None, params: Iterable[str],
                    base_config: Any, manifest: str | Path | None = None, xi: float = 0.75,
                    save: Iterable[str] = (), scoring: str = DEFAULT_SCORING) -> Study:
    """Build a :class:`Study` from command-line style inputs (``SOURCE``, ``--gt``, ``--param``,
    ``--sequences``)."""
    seqs: list[SequenceSpec] = []
    gts = list(gt or [])
    if manifest is not None:
        seqs.extend(read_manifest(manifest))
    if sources:
        if gts and len(gts) != len(sources):
            raise ConfigError(f"give one --gt per SOURCE ({len(sources)} sources, {len(gts)} --gt)")
        for i, s in enumerate(sources):
            g = gts[i] if gts else None
            src = s if s.startswith("synth:") else absolute_path(s)
            seqs.append(SequenceSpec(name=default_sequence_name(s), source=src, gt=absolute_path(g)))
    if not seqs:
        raise ConfigError("give a SOURCE or --sequences manifest.toml")
    names = [s.name for s in seqs]
    if len(set(names)) != len(names):  # make derived names unique: name, name-2, ...
        seen: dict[str, int] = {}
        fixed = []
        for s in seqs:
            seen[s.name] = seen.get(s.name, 0) + 1
            nm = s.name if seen[s.name] == 1 else f"{s.name}-{seen[s.name]}"
            fixed.append(SequenceSpec(nm, s.source, s.gt, s.group))
        seqs = fixed
    check_ground_truth(seqs)
    grid = tuple(parse_param(p) for p in params)
    study = Study(sequences=tuple(seqs), grid=grid, base_config=to_dict(base_config), xi=xi,
                  save=tuple(save), scoring=scoring)
    # a key no grid point switches on would score the same in every run
    check_study_keys(study.base_config, dict(grid), "sweep")
    return study
