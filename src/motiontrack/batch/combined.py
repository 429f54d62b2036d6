"""The metrics of a batch's videos with ground truth combined as TrackEval combines sequences.

Each finished video with ground truth has ``gt.txt`` and ``tracks.txt`` in its folder; every
such sequence is scored over the frames its run's accuracy covered (the frames the run
processed that the ground truth covers, as ``track --gt`` scores them:
:func:`~motiontrack.evaluate.score.scored_frames`) and the sequences are combined with
:func:`motiontrack.evaluate.mot.combine_sequences` in name order, as ``evaluate --gt-folder``
reports ``COMBINED``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping, Sequence

from ..evaluate import mot
from ..evaluate.score import scored_frames
from ..evaluate.scoring import DEFAULT_SCORING, ignores_zero_marked
from ..io.atomic import atomic_write_text
from ..io.mot import read_mot
from ..run.folder import RunFolder

__all__ = ["COMBINED_FILE", "combined_metrics", "write_combined"]

COMBINED_FILE = "combined.json"
#: the index statuses of a video whose folder holds its run
FINISHED = ("done", "truncated")


def _sequence(folder: Path, summary: Mapping[str, Any]) -> dict[str, dict]:
    run = RunFolder(folder)
    gt = read_mot(run.gt, kind="gt")
    pred = read_mot(run.tracks, kind="results")   # empty: found nothing
    window = (summary.get("accuracy") or {}).get("frames_scored")
    if isinstance(window, list) and len(window) == 2 and all(isinstance(f, int) for f in window):
        # the frames the run's own accuracy covers: a gt.txt beside the run does not say how long
        # its scene was (a synthetic scene's last frames may hold nobody)
        gt, pred, _ = scored_frames(gt, pred, (window[0], window[1]), outside=True)
    else:
        gt, pred, _ = scored_frames(gt, pred, (1, int(summary["frames"])))
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
        summary = RunFolder(folder).summary() or {}
        try:
            int(summary["frames"])
        except (ValueError, KeyError, TypeError):
            continue
        per[r["name"]] = _sequence(folder, summary)
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
