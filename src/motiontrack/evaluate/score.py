"""The frames a score covers, and one run's score as ``motiontrack track --gt`` reports it.

Every command that scores tracks against ground truth (``evaluate --gt``, ``track --gt``,
``sweep``, ``tune``, ``batch``) scores the frames :func:`scored_frames` chooses: those the
ground truth covers (its first to last frame, or frames 1 to the ``seqLength`` of a MOTChallenge
``seqinfo.ini`` beside it or a synthetic scene's length, ``meta["seq_length"]``), within the
frames asked for (``--frames``, or the frames a run processed). Predictions outside the ground truth are left out rather than
counted as false positives: a run of 795 frames against ground truth of frames 1–300 would
otherwise count every box of the 495 frames nobody annotated as wrong.
``evaluate --score-outside-gt`` counts them.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ..types import Annotations
from .mot import evaluate_tracking
from .scoring import DEFAULT_SCORING, ignores_zero_marked

log = logging.getLogger(__name__)

__all__ = ["RUN_KEYS", "ScoredFrames", "gt_coverage", "scored_frames", "score_run"]

#: the metrics a run's summary reports, besides recall and precision
RUN_KEYS = ("HOTA", "MOTA", "IDF1", "MOTP", "DetA", "AssA", "IDSW", "TP", "FP", "FN")


@dataclass(frozen=True)
class ScoredFrames:
    """The frames a score covers: ``first`` to ``last`` (1-based, inclusive; ``None`` = open),
    the predicted frames and boxes within the frames asked for that were left out because the
    ground truth does not cover them, and the frames it covers (``covered``; None when nothing
    restricted the score to them)."""

    first: int | None
    last: int | None
    left_out_frames: int = 0
    left_out_boxes: int = 0
    covered: tuple[int, int] | None = None
    from_length: bool = False

    @property
    def empty(self) -> bool:
        """No frame is scored: the frames asked for and the ground truth's do not meet."""
        return self.first is not None and self.last is not None and self.first > self.last

    def note(self) -> str:
        """The one line that says what was left out (empty when nothing was)."""
        where = "the ground truth's sequence" if self.from_length else "the ground truth"
        if self.empty and self.covered is not None:
            c = self.covered
            return (f"no frame asked for is among the frames of {where} ({c[0]}–{c[1]}): "
                    f"nothing scored")
        if not self.left_out_frames:
            return ""
        return (f"scored frames {self.first}–{self.last} of {where}; {self.left_out_frames} "
                f"predicted frame{'s' if self.left_out_frames != 1 else ''} outside it "
                f"({self.left_out_boxes} box{'es' if self.left_out_boxes != 1 else ''}) "
                f"{'were' if self.left_out_frames != 1 else 'was'} left out")

    def as_dict(self) -> dict[str, object]:
        """The window as ``summary.json`` records it."""
        d: dict[str, object] = {"frames_scored": [self.first, self.last]}
        if self.left_out_frames:
            d["left_out_frames"] = self.left_out_frames
        return d


def gt_coverage(gt: Annotations) -> tuple[int, int] | None:
    """The frames the ground truth covers: 1 to ``gt.meta["seq_length"]`` when its sequence's
    length is known (a ``seqinfo.ini`` beside the file,
    :func:`~motiontrack.io.annotations.read_ground_truth`; a synthetic scene's frames), else its
    first to last frame; None for empty ground truth."""
    length = gt.meta.get("seq_length")
    last = int(gt.frames.max()) if len(gt) else 0
    if isinstance(length, int) and length >= 1:
        return 1, max(length, last)   # rows past the stated length are still ground truth
    if len(gt) == 0:
        return None
    return int(gt.frames.min()), last


def _within(ann: Annotations, lo: int | None, hi: int | None) -> np.ndarray:
    keep = np.ones(len(ann), dtype=bool)
    if lo is not None:
        keep &= ann.frames >= lo
    if hi is not None:
        keep &= ann.frames <= hi
    return keep


def scored_frames(gt: Annotations, pred: Annotations,
                  frames: tuple[int | None, int | None] | None = None,
                  outside: bool = False) -> tuple[Annotations, Annotations, ScoredFrames]:
    """Ground truth and predictions restricted to the frames a score covers.

    Parameters
    ----------
    gt, pred : ground truth and predictions (1-based frames).
    frames : the frames asked for, ``(first, last)`` inclusive (either None = open), or None
        for all.
    outside : keep the predictions outside the ground truth's frames (they then count as false
        positives); only ``frames`` restricts.

    Returns
    -------
    gt, pred, ScoredFrames
        Both tables within the scored frames, and the window with what was left out.
    """
    lo, hi = frames if frames is not None else (None, None)
    cover = None if outside else gt_coverage(gt)
    if cover is not None:
        lo = cover[0] if lo is None else max(lo, cover[0])
        hi = cover[1] if hi is None else min(hi, cover[1])
    asked = _within(pred, *(frames if frames is not None else (None, None)))
    kept = _within(pred, lo, hi)
    dropped = asked & ~kept
    window = ScoredFrames(lo, hi, int(len(np.unique(pred.frames[dropped]))),
                          int(np.count_nonzero(dropped)), covered=cover,
                          from_length=cover is not None and "seq_length" in gt.meta)
    return gt.select(_within(gt, lo, hi)), pred.select(kept), window


def score_run(gt: Annotations, pred: Annotations, frames: int, start: int = 0,
              scoring: str = DEFAULT_SCORING) -> dict[str, float | str]:
    """Accuracy of a run's tracks against ground truth over the processed frames the ground
    truth covers (:func:`scored_frames`).

    Parameters
    ----------
    gt, pred : ground truth and tracks (1-based frame numbers).
    frames : how many frames the run processed.
    start : the 0-based index of the first processed frame (``--start``).
    scoring : how zero-marked gt rows count, a name of
        :data:`~motiontrack.evaluate.scoring.SCORING`.

    Returns
    -------
    dict of :data:`RUN_KEYS` plus ``recall`` and ``precision`` (CLEAR's ``CLR_Re``/``CLR_Pr``),
    ``scoring``, the convention's name, and the window (:meth:`ScoredFrames.as_dict`).
    """
    ignore = ignores_zero_marked(scoring)
    gt, pred, window = scored_frames(gt, pred, (start + 1, start + frames))
    if window.note():
        log.info("accuracy: %s", window.note())
    res = evaluate_tracking(gt, pred, ignore_zero_marked=ignore)
    out: dict[str, float | str] = {k: float(res[k]) for k in RUN_KEYS if k in res}
    out["recall"] = float(res.get("recall", 0.0))
    out["precision"] = float(res.get("precision", 0.0))
    out["scoring"] = scoring
    out.update(window.as_dict())
    return out
