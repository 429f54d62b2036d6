"""Benchmark-level tracking metrics: one tracker over many sequences, combined as TrackEval does.

TrackEval (``Evaluator.evaluate`` with ``MotChallenge2DBox``) scores every sequence on its own,
with the sequence length taken from ``seqinfo.ini``, then combines the per-sequence results of
the sorted sequence list with each metric's ``combine_sequences``: counts summed, ratios
recomputed, HOTA's association and localisation scores weighted by each sequence's TP
(:func:`motiontrack.evaluate.mot.combine_sequences`). The order matters only to floating-point
rounding, and it is TrackEval's here.

Pure functions over already-read :class:`~motiontrack.types.Annotations`; the folder layout is
:mod:`motiontrack.io.mot_layout`'s.
"""

from __future__ import annotations

from typing import Iterable, Mapping

from ..errors import InputError
from ..types import Annotations
from . import mot

__all__ = ["COMBINED", "check_length", "evaluate_tracker", "flatten_benchmark"]

#: the key of the combined result, next to the sequence names
COMBINED = "COMBINED"


def check_length(ann: Annotations, length: int, what: str) -> None:
    """Refuse frames beyond the sequence length (TrackEval: "invalid timesteps")."""
    if len(ann) and int(ann.frames.max()) > length:
        raise InputError(f"{what} has frame {int(ann.frames.max())}, beyond the sequence's "
                         f"seqLength {length}")


def evaluate_tracker(
    gt: Mapping[str, Annotations],
    lengths: Mapping[str, int],
    pred: Mapping[str, Annotations],
    metrics: Iterable[str] = mot.METRIC_FAMILIES,
    ignore_zero_marked: bool = False,
) -> dict[str, dict[str, dict]]:
    """One tracker on every sequence of ``gt``, and the sequences combined.

    Parameters
    ----------
    gt : {sequence: Annotations}
        Ground truth per sequence.
    lengths : {sequence: int}
        Number of frames of each sequence (``seqLength``).
    pred : {sequence: Annotations}
        The tracker's output for each sequence of ``gt`` (an empty table: found nothing).
    metrics, ignore_zero_marked
        As :func:`motiontrack.evaluate.mot.evaluate_sequence`.

    Returns
    -------
    {sequence: {family: {field: value}}, "COMBINED": {...}}
        Sequences in sorted order, then ``COMBINED``; TrackEval's field names.
    """
    metrics = tuple(metrics)
    out: dict[str, dict[str, dict]] = {}
    for seq in sorted(gt):
        if seq not in pred:
            raise InputError(f"no tracker output for sequence {seq}")
        check_length(pred[seq], lengths[seq], f"tracker output of {seq}")
        check_length(gt[seq], lengths[seq], f"ground truth of {seq}")
        try:
            out[seq] = mot.evaluate_sequence(gt[seq], pred[seq], metrics,
                                             num_timesteps=lengths[seq],
                                             ignore_zero_marked=ignore_zero_marked)
        except InputError as exc:  # a duplicate id: say in which sequence
            raise InputError(f"sequence {seq}: {exc}") from None
    out[COMBINED] = mot.combine_sequences(out.values())
    return out


def flatten_benchmark(results: Mapping[str, Mapping[str, Mapping]]) -> dict[str, dict[str, float]]:
    """:func:`evaluate_tracker`'s result with each entry flattened (:func:`mot.flatten` keys)."""
    return {seq: mot.flatten(res) for seq, res in results.items()}
