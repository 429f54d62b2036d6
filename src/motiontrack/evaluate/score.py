"""Scoring one run's tracks against its ground truth, as ``motiontrack track --gt`` reports it."""

from __future__ import annotations

from ..types import Annotations
from .mot import evaluate_tracking
from .scoring import DEFAULT_SCORING, ignores_zero_marked

__all__ = ["RUN_KEYS", "score_run"]

#: the metrics a run's summary reports, besides recall and precision
RUN_KEYS = ("HOTA", "MOTA", "IDF1", "MOTP", "DetA", "AssA", "IDSW", "TP", "FP", "FN")


def score_run(gt: Annotations, pred: Annotations, frames: int, start: int = 0,
              scoring: str = DEFAULT_SCORING) -> dict[str, float | str]:
    """Accuracy of a run's tracks against ground truth restricted to the processed frames.

    Parameters
    ----------
    gt, pred : ground truth and tracks (1-based frame numbers).
    frames : how many frames the run processed.
    start : the 0-based index of the first processed frame (``--start``).
    scoring : how zero-marked gt rows count, a name of
        :data:`~motiontrack.evaluate.scoring.SCORING`.

    Returns
    -------
    dict of :data:`RUN_KEYS` plus ``recall`` and ``precision`` (CLEAR's ``CLR_Re``/``CLR_Pr``)
    and ``scoring``, the convention's name.
    """
    ignore = ignores_zero_marked(scoring)
    lo, hi = start + 1, start + frames
    gt = gt.select((gt.frames >= lo) & (gt.frames <= hi))
    res = evaluate_tracking(gt, pred, ignore_zero_marked=ignore)
    out: dict[str, float | str] = {k: float(res[k]) for k in RUN_KEYS if k in res}
    out["recall"] = float(res.get("recall", 0.0))
    out["precision"] = float(res.get("precision", 0.0))
    out["scoring"] = scoring
    return out
