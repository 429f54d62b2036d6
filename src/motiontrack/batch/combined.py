"""The metrics of a batch's videos with ground truth combined as TrackEval combines sequences.

Each finished video with ground truth has ``gt.txt`` and ``tracks.txt`` in its folder; every
such sequence is scored (restricted to the frames the run processed, the scoring ``track``
uses) and the sequences are combined with :func:`motiontrack.evaluate.mot.combine_sequences`
in name order, as ``evaluate --gt-folder`` reports ``COMBINED``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping, Sequence

from ..evaluate import mot
from ..evaluate.scoring import DEFAULT_SCORING, ignores_zero_marked
from ..io.atomic import atomic_write_text
from ..io.mot import read_mot
from ..run.folder import RunFolder

__all__ = ["COMBINED_FILE", "combined_metrics", "write_combined"]

COMBINED_FILE = "combined.json"
#: the index statuses of a video whose folder holds its run
FINISHED = ("done", "truncated")


def _sequence(folder: Path, frames: int) -> dict[str, dict]:
    run = RunFolder(folder)
    gt = read_mot(run.gt, kind="gt")
    pred = read_mot(run.tracks, kind="results")   # empty: found nothing
    gt = gt.select((gt.frames >= 1) & (gt.frames <= frames))
    return mot.evaluate_sequence(gt, pred,
                                 ignore_zero_marked=ignores_zero_marked(DEFAULT_SCORING))


def combined_metrics(results: Path, rows: Sequence[Mapping[str, Any]]) -> dict[str, Any] | None:
    """``{"sequences": [names], "metrics": {flat metrics}}`` over the finished videos (``done``,
    and ``truncated`` over the frames they hold) whose folder holds ground truth, or None when
    none does."""
    per: dict[str, dict[str, dict]] = {}
    for r in sorted(rows, key=lambda r: r["name"]):
        folder = Path(results) / r["name"]
        if r.get("status") not in FINISHED or not RunFolder(folder).gt.is_file():
            continue
        try:
            frames = int((RunFolder(folder).summary() or {})["frames"])
        except (ValueError, KeyError, TypeError):
            continue
        per[r["name"]] = _sequence(folder, frames)
    if not per:
        return None
    return {"sequences": list(per), "metrics": mot.flatten(mot.combine_sequences(per.values()))}


def write_combined(results: Path, rows: Sequence[Mapping[str, Any]]) -> dict[str, Any] | None:
    """:func:`combined_metrics` written to ``RESULTS/combined.json`` (removed when no video has
    ground truth); returns it."""
    combined = combined_metrics(results, rows)
    path = Path(results) / COMBINED_FILE
    if combined is None:
        path.unlink(missing_ok=True)
    else:
        atomic_write_text(path, json.dumps(combined, indent=2) + "\n")
    return combined
