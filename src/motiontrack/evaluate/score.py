"""Scoring one run's tracks against its ground truth, as ``motiontrack track --gt`` reports it."""

from __future__ import annotations

from ..types import Annotations
from .mot import evaluate_tracking

__all__ = ["RUN_KEYS", "score_run"]

#: the metrics a run's summary reports, besides recall and precision
RUN_KEYS = ("HOTA", "MOTA", "IDF1", "MOTP", "DetA", "AssA", "IDSW", "TP", "FP", "FN")


def score_run(gt: Annotations, pred: Annotations, frames: int, start: int = 0) -> dict[str, float]:
    """Accuracy of a run's tracks against ground truth restricted to the processed frames.

    Parameters
    ----------
    gt, pred : ground truth and tracks (1-based frame numbers).
    frames : how many frames the run processed.
    start : the 0-based index of the first processed frame (``--start``).

    Returns
    -------
    dict of :data:`RUN_KEYS` plus ``recall`` and ``precision`` (CLEAR's ``CLR_Re``/``CLR_Pr``).
    """
    lo, hi = start + 1, start + frames
    gt = gt.select((gt.frames >= lo) & (gt.frames <= hi))
    # rows with consider = 0 (occluded synthetic people, PETS people outside the area) are
    # ignore regions: a box on them is neither a hit nor a false positive
    res = evaluate_tracking(gt, pred, ignore_zero_marked=True)
    out = {k: float(res[k]) for k in RUN_KEYS if k in res}
    out["recall"] = float(res.get("recall", 0.0))
    out["precision"] = float(res.get("precision", 0.0))
    return out
