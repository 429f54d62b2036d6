"""Ablation: what each people module contributes (the thesis' figures 4.15/4.16).

The pipeline runs with the people modules switched on one after another (:data:`ROWS`, cumulative
as in the thesis) and each run is scored by the localized object precision and recall (ξ = 0.75,
the thesis' measure) of the tracker output, plus recall/precision, MOTA, IDF1 and HOTA.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

from ..config import PipelineConfig, load_config, to_dict
from ..errors import ConfigError
from ..evaluate.scoring import DEFAULT_SCORING, ignores_zero_marked
from ..io.manifest import SequenceSpec
from .params import parse_param
from .sweep import RunSpec, execute

__all__ = ["ROWS", "COLUMNS", "select_rows", "row_settings", "run_ablation", "format_table",
           "AblationInterrupted"]

#: rows of the table: label → overrides (cumulative, as in the thesis)
ROWS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("motion + regions only", ("people.enabled=false", "people.auto_split=false")),
    ("+ head detector", ("people.enabled=true", "people.heads=true", "people.split=false",
                         "people.shapes=false")),
    ("+ head-based splitting", ("people.enabled=true", "people.heads=true", "people.split=true",
                                "people.shapes=false")),
    ("+ active shape tracker", ("people.enabled=true", "people.heads=true", "people.split=true",
                                "people.shapes=true")),
    ("+ shape hypotheses", ("people.enabled=true", "people.heads=true", "people.split=true",
                            "people.shapes=true", "people.hypotheses=true")),
    ("+ HOG in regions", ("people.enabled=true", "people.heads=true", "people.split=true",
                          "people.shapes=true", "people.hypotheses=true", "people.hog=regions",
                          "people.hog_every=5")),
    # not cumulative: the default pipeline, whose regions are split between heads in upright scenes
    ("default (automatic head splitting)", ("people.enabled=false", "people.auto_split=true")),
)

#: table column → its short heading
COLUMNS: dict[str, str] = {
    "localized_object_precision": "LOP", "localized_object_recall": "LOR", "recall": "recall",
    "precision": "prec", "MOTA": "MOTA", "IDF1": "IDF1", "HOTA": "HOTA",
}


def select_rows(text: str | None) -> list[tuple[str, tuple[str, ...]]]:
    """The rows named by ``"1,3"`` (1-based), or all of them for None or an empty string."""
    if not text:
        return list(ROWS)
    try:
        pick = [int(r) for r in text.split(",")]
    except ValueError:
        raise ConfigError(f"--rows expects numbers like 1,3, got {text!r}") from None
    if any(not 1 <= r <= len(ROWS) for r in pick):
        raise ConfigError(f"--rows must be between 1 and {len(ROWS)}")
    return [ROWS[r - 1] for r in pick]


def row_settings(rows: Sequence[tuple[str, tuple[str, ...]]]) -> list[dict[str, Any]]:
    """The settings of each row as ``{key: value}`` (what the row changes in the base config)."""
    return [{key: values[0] for key, values in map(parse_param, overrides)}
            for _label, overrides in rows]


def run_ablation(source: str, gt: str | None, base: PipelineConfig,
                 rows: Sequence[tuple[str, tuple[str, ...]]] = ROWS, xi: float = 0.75,
                 jobs: int = 1, scoring: str = DEFAULT_SCORING) -> list[dict[str, Any]]:
    """Run every row on ``source`` and score it; one dict per row with ``configuration``, the
    :data:`COLUMNS` and ``scoring``, how zero-marked ground truth counted in the tracking metrics
    (:data:`~motiontrack.evaluate.scoring.SCORING`)."""
    if not 0.0 <= xi <= 1.0:
        raise ConfigError(f"--xi must be in [0, 1], got {xi}")
    ignores_zero_marked(scoring)
    seq = SequenceSpec("seq", source, gt)
    specs = []
    for k, (_label, overrides) in enumerate(rows):
        load_config(None, overrides)  # validate before any run
        params = tuple((key, values[0]) for key, values in map(parse_param, overrides))
        specs.append(RunSpec(run=k, params=params, sequence=seq, base_config=to_dict(base), xi=xi,
                             scoring=scoring))
    done: dict[int, dict[str, Any]] = {}

    def finished(i: int, res: dict[str, Any]) -> None:
        done[i] = _row(rows[i][0], res["row"], scoring)

    try:
        execute(specs, jobs=jobs, on_result=finished)
    except KeyboardInterrupt:
        raise AblationInterrupted([done[i] for i in sorted(done)], len(rows)) from None
    return [done[i] for i in range(len(rows))]


class AblationInterrupted(KeyboardInterrupt):
    """An ablation stopped by Ctrl-C or SIGTERM: ``table`` holds the rows that finished (in row
    order) out of ``total``."""

    def __init__(self, table: list[dict[str, Any]], total: int) -> None:
        super().__init__(f"interrupted after {len(table)} of {total} rows")
        self.table, self.total = table, total


def _row(label: str, r: Mapping[str, Any], scoring: str) -> dict[str, Any]:
    tp, fp, fn = r["TP"], r["FP"], r["FN"]
    return {
        "configuration": label,
        "localized_object_precision": r["trk_localized_object_precision"],
        "localized_object_recall": r["trk_localized_object_recall"],
        "recall": tp / (tp + fn) if tp + fn else 0.0,
        "precision": tp / (tp + fp) if tp + fp else 0.0,
        "MOTA": r["MOTA"], "IDF1": r["IDF1"], "HOTA": r["HOTA"],
        "scoring": scoring,
    }


def format_table(table: Sequence[Mapping[str, Any]]) -> str:
    """The rows as a fixed-width text table, one line per configuration, then the scoring
    convention of the tracking metrics."""
    w = max([len("configuration")] + [len(t["configuration"]) for t in table])
    out = [f"{'configuration':<{w}}  " + " ".join(f"{h:>7}" for h in COLUMNS.values())]
    for t in table:
        out.append(f"{t['configuration']:<{w}}  " + " ".join(f"{t[c]:>7.3f}" for c in COLUMNS))
    scorings = list(dict.fromkeys(t["scoring"] for t in table if "scoring" in t))
    if scorings:
        out.append(f"scoring {', '.join(scorings)}")
    return "\n".join(out) + "\n"
