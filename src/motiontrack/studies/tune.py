"""Automatic parameter tuning with Optuna (optional extra: ``pip install optuna``).

The thesis tunes the motion detector by hand from sweeps (§4.4). :func:`tune` searches the same
parameter space automatically: a seeded TPE sampler proposes configurations, each is run on the
*training* sequences and scored by the mean of one table metric (any column of a sweep table, e.g.
``det_object_f1``, ``det_pixel_f1``, ``HOTA``); the best configuration is then run once on separate
*validation* sequences, whose score is the honest estimate, and written as a TOML config usable with
``motiontrack track --config``.

Search-space syntax (one ``--param`` per parameter; the values syntax of ``sweep --param``,
plus the ranges a grid cannot enumerate)::

    motion.median.threshold=0.02:0.4        float range (uniform)
    regions.min_area=50:2000:log            range sampled on a log scale
    cleanup.dilate_iterations=0:4           integer range (both ends integers)
    motion.median.threshold=0.02:0.2:0.02   stepped range (the values of the sweep grid 0.02:0.2:0.02)
    motion.method=median,mog2               categorical
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass, field
from decimal import Decimal
from pathlib import Path
from typing import Any, Callable, Sequence

from ..config import PipelineConfig, apply_overrides, from_dict, save_config, to_dict
from ..config_activity import check_study_keys
from ..errors import ConfigError
from ..evaluate.scoring import DEFAULT_SCORING, ignores_zero_marked
from ..io.atomic import atomic_write_text
from ..io.manifest import SequenceSpec
from .params import format_value, parse_literal, range_values
from .sweep import RunSpec, check_ground_truth, execute
from .table import write_table

log = logging.getLogger(__name__)

__all__ = ["SearchParam", "parse_space", "tune", "TuneResult", "require_optuna"]


def require_optuna():
    """Import optuna or raise a ConfigError saying how to install it."""
    try:
        import optuna
    except ImportError:
        raise ConfigError("motiontrack tune needs Optuna: pip install optuna") from None
    return optuna


@dataclass(frozen=True)
class SearchParam:
    """One dimension of the search space."""

    key: str
    kind: str  # "float" | "int" | "categorical"
    low: float = 0.0
    high: float = 0.0
    log: bool = False
    choices: tuple[Any, ...] = ()
    step: float | None = None  # a stepped range: low, low + step, ..., high

    def __post_init__(self) -> None:
        if self.kind not in ("float", "int", "categorical"):
            raise ConfigError(f"search parameter kind must be float, int or categorical, got {self.kind!r}")
        if self.kind == "categorical":
            if not self.choices:
                raise ConfigError(f"--param {self.key}: no choices")
        else:
            if not (math.isfinite(self.low) and math.isfinite(self.high)) or self.high < self.low:
                raise ConfigError(f"--param {self.key}: need finite lo <= hi, got {self.low}:{self.high}")
            if self.log and self.low <= 0:
                raise ConfigError(f"--param {self.key}: a log range needs lo > 0, got {self.low}")
            if self.step is not None and (self.log or not self.step > 0):
                raise ConfigError(f"--param {self.key}: a stepped range needs a step > 0 and no "
                                  f"log scale, got step {self.step}")

    def suggest(self, trial: Any) -> Any:
        if self.kind == "float":
            return self.value_of(trial.suggest_float(self.key, self.low, self.high, log=self.log,
                                                     step=self.step))
        if self.kind == "int":
            return trial.suggest_int(self.key, int(self.low), int(self.high), log=self.log,
                                     step=int(self.step or 1))
        return trial.suggest_categorical(self.key, list(self.choices))

    def value_of(self, proposed: Any) -> Any:
        """The value a proposal of Optuna stands for: on a stepped float range the grid value
        computed in decimal, as ``sweep`` computes it (Optuna's ``low + k * step`` drifts:
        0.06000000000000001); otherwise the proposal itself."""
        if self.kind != "float" or self.step is None:
            return proposed
        k = round((proposed - self.low) / self.step)
        return float(Decimal(repr(self.low)) + k * Decimal(repr(self.step)))

    @property
    def domain(self) -> tuple[Any, ...]:
        """Values that stand for the dimension when asking which keys it can switch on: the
        choices, or a range's two ends."""
        return self.choices or (self.low, self.high)


def parse_space(item: str) -> SearchParam:
    """Parse ``key=lo:hi[:log]``, ``key=lo:hi:step`` or ``key=a,b,c`` (see the module doc)."""
    if "=" not in item:
        raise ConfigError(f"--param expects stage.name=lo:hi or stage.name=a,b,..., got {item!r}")
    key, text = (s.strip() for s in item.split("=", 1))
    if not key or not text:
        raise ConfigError(f"--param expects stage.name=lo:hi or stage.name=a,b,..., got {item!r}")
    if ":" in text and "," not in text:
        parts = [p.strip() for p in text.split(":")]
        use_log = len(parts) == 3 and parts[2].lower() == "log"
        if len(parts) not in (2, 3):
            raise ConfigError(f"--param {item!r}: a range is lo:hi, lo:hi:log or lo:hi:step")
        try:
            lo, hi = float(parts[0]), float(parts[1])
        except ValueError:
            raise ConfigError(f"--param {item!r}: lo and hi must be numbers") from None
        if len(parts) == 3 and not use_log:
            # the values of the sweep grid lo:hi:step (hi is the last of them, as in the grid)
            values = range_values(*parts, item=item)
            kind = "int" if isinstance(values[0], int) else "float"
            return SearchParam(key, kind, lo, float(values[-1]), step=float(parts[2]))
        is_int = all(p.lstrip("+-").isdigit() for p in parts[:2])
        return SearchParam(key, "int" if is_int else "float", lo, hi, log=use_log)
    choices = tuple(parse_literal(p.strip()) for p in text.split(",") if p.strip())
    if not all(isinstance(c, (bool, int, float, str)) for c in choices):
        raise ConfigError(f"--param {item!r}: choices must be numbers, booleans or strings")
    if len(set(map(repr, choices))) != len(choices):
        raise ConfigError(f"--param {item!r} repeats a choice")
    return SearchParam(key, "categorical", choices=choices)


@dataclass(frozen=True)
class TuneResult:
    """Best configuration of a tuning run and its scores."""

    metric: str
    direction: str
    best_params: dict[str, Any]
    train_score: float
    validation_score: float | None
    trials: list[dict[str, Any]] = field(repr=False)
    validation_rows: list[dict[str, Any]] = field(repr=False)
    best_config: Any = field(repr=False, default=None)
    scoring: str = DEFAULT_SCORING
    #: the search was stopped (Ctrl-C, SIGTERM): the best of the trials finished before it,
    #: not validated
    interrupted: bool = False

    def as_dict(self) -> dict[str, Any]:
        return {"metric": self.metric, "direction": self.direction, "best_params": self.best_params,
                "train_score": self.train_score, "validation_score": self.validation_score,
                "n_trials": len(self.trials), "scoring": self.scoring,
                "interrupted": self.interrupted}


def _check_key(base: dict[str, Any], key: str) -> None:
    """:class:`ConfigError` when ``key`` names no field of the config ``base`` (as a dict): every
    trial would be invalid, and the search would end with nothing to say why."""
    node: Any = base
    parts = key.split(".")
    for i, part in enumerate(parts):
        if not isinstance(node, dict) or part not in node:
            raise ConfigError(f"--param {key}: unknown config key {'.'.join(parts[:i + 1])!r}")
        node = node[part]
    if isinstance(node, dict):
        valid = sorted(k for k, v in node.items() if not isinstance(v, dict))
        raise ConfigError(f"--param {key}: a config section, not a key; valid keys here: "
                          f"{', '.join(valid)}")


def _score(rows: Sequence[dict[str, Any]], metric: str) -> float:
    if rows and metric not in rows[0]:
        raise ConfigError(f"unknown metric {metric!r}; choose a table column such as det_object_f1, "
                          f"det_pixel_f1, HOTA, MOTA, IDF1")
    vals = [float(r[metric]) for r in rows]
    vals = [v for v in vals if not math.isnan(v)]
    return sum(vals) / len(vals) if vals else float("nan")


def _checked_search(train: Sequence[SequenceSpec], validation: Sequence[SequenceSpec],
                    space: Sequence[SearchParam], base_config: Any, *, direction: str,
                    n_trials: int, xi: float, jobs: int, scoring: str) -> dict[str, Any]:
    """The base config of a search as a dict, once every argument of :func:`tune` is checked
    (:class:`ConfigError` for the first that is wrong): here rather than in the first trial,
    whose failure Optuna would log as its own."""
    if not train:
        raise ConfigError("tune needs at least one training sequence")
    if not space:
        raise ConfigError("tune needs at least one --param")
    if direction not in ("maximize", "minimize"):
        raise ConfigError(f"direction must be maximize or minimize, got {direction!r}")
    if n_trials < 1:
        raise ConfigError(f"--trials must be >= 1, got {n_trials}")
    if jobs < 1:
        raise ConfigError(f"-j must be >= 1, got {jobs}")
    if not 0.0 <= xi <= 1.0:
        raise ConfigError(f"--xi must be in [0, 1], got {xi}")
    ignores_zero_marked(scoring)
    keys = [p.key for p in space]
    if len(set(keys)) != len(keys):
        raise ConfigError(f"--param keys must be distinct, got {keys}")
    base = to_dict(base_config)
    for key in keys:
        _check_key(base, key)
    # a key no point of the space switches on: every trial would score the same
    check_study_keys(base, {p.key: p.domain for p in space}, "search")
    check_ground_truth([*train, *validation])
    return base


def tune(train: Sequence[SequenceSpec], validation: Sequence[SequenceSpec], space: Sequence[SearchParam],
         base_config: Any, *, metric: str = "det_object_f1", direction: str = "maximize",
         n_trials: int = 20, seed: int = 0, xi: float = 0.75, jobs: int = 1,
         progress: Callable[[int], None] | None = None,
         scoring: str = DEFAULT_SCORING) -> TuneResult:
    """Search ``space`` for the configuration with the best mean ``metric`` on ``train``.

    Parameters
    ----------
    train, validation : sequences (validation may be empty: no validation score).
    space : search dimensions (:func:`parse_space`).
    base_config : PipelineConfig the parameters are applied to.
    metric : a column of the sweep table; averaged over the training sequences.
    direction : ``"maximize"`` or ``"minimize"``.
    n_trials : number of configurations tried.
    seed : seed of the TPE sampler (same seed, same trials).
    jobs : processes used to run the training sequences of one trial in parallel.
    progress : called with 1 after each trial.
    scoring : how zero-marked ground truth counts in the tracking metrics
        (:data:`~motiontrack.evaluate.scoring.SCORING`).
    """
    optuna = require_optuna()
    base = _checked_search(train, validation, space, base_config, direction=direction,
                           n_trials=n_trials, xi=xi, jobs=jobs, scoring=scoring)

    def specs(params: dict[str, Any], seqs: Sequence[SequenceSpec], run: int) -> list[RunSpec]:
        return [RunSpec(run=run, params=tuple(params.items()), sequence=s, base_config=base, xi=xi,
                        scoring=scoring)
                for s in seqs]

    trials: list[dict[str, Any]] = []

    def objective(trial: Any) -> float:
        params = {p.key: p.suggest(trial) for p in space}
        try:
            apply_overrides(base_config, [f"{k}={format_value(v)}" for k, v in params.items()])
        except ConfigError as exc:  # outside a field's range: an invalid point, not a crash
            log.debug("trial %d invalid: %s", trial.number, exc)
            trials.append({"trial": trial.number, **params, metric: float("nan"), "state": "invalid"})
            raise optuna.TrialPruned(str(exc)) from None
        rows = [r["row"] for r in execute(specs(params, train, trial.number + 1), jobs=jobs)]
        score = _score(rows, metric)
        trials.append({"trial": trial.number, **params, metric: score,
                       "state": "complete" if not math.isnan(score) else "undefined"})
        if progress is not None:
            progress(1)
        if math.isnan(score):
            raise optuna.TrialPruned(f"{metric} undefined")
        return score

    sampler = optuna.samplers.TPESampler(seed=seed)
    study = optuna.create_study(direction=direction, sampler=sampler)
    interrupted = False
    try:
        study.optimize(objective, n_trials=n_trials)
    except KeyboardInterrupt:   # the trial in progress is dropped; the finished ones stand
        interrupted = True
    if not any(t["state"] == "complete" for t in trials):
        if interrupted:
            raise KeyboardInterrupt
        raise ConfigError(f"no trial gave a defined {metric}; widen the search space")
    dims = {p.key: p for p in space}
    best = {k: dims[k].value_of(v) for k, v in study.best_params.items()}
    # values of the best trial in the original types (Optuna returns the suggested python values)
    best_cfg = apply_overrides(from_dict(PipelineConfig, base),
                               [f"{k}={format_value(v)}" for k, v in best.items()])
    validate = bool(validation) and not interrupted
    val_rows = [r["row"] for r in execute(specs(best, validation, 0), jobs=jobs)] if validate else []
    val_score = _score(val_rows, metric) if validate else None
    return TuneResult(metric=metric, direction=direction, best_params=best,
                      train_score=float(study.best_value), validation_score=val_score,
                      trials=trials, validation_rows=val_rows, best_config=best_cfg,
                      scoring=scoring, interrupted=interrupted)


def write_tune_outputs(res: TuneResult, out_dir: str | Path) -> dict[str, str]:
    """``best_config.toml`` (usable with ``motiontrack track --config``), ``tune.json``,
    ``trials.csv`` and ``validation.csv`` in ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"config": str(out / "best_config.toml"), "summary": str(out / "tune.json"),
             "trials": str(out / "trials.csv")}
    save_config(res.best_config, paths["config"])
    atomic_write_text(paths["summary"], json.dumps(res.as_dict(), indent=2, default=str) + "\n")
    cols: list[str] = []
    for t in res.trials:
        cols += [c for c in t if c not in cols]
    write_table([{c: t.get(c, "") for c in cols} for t in res.trials], paths["trials"])
    if res.validation_rows:
        paths["validation"] = str(out / "validation.csv")
        write_table(res.validation_rows, paths["validation"])
    return paths
