"""The two conventions for zero-marked ground truth every scoring command offers (``--scoring``).

A light module (no numerical imports), so that the command line can list the names without
loading the metrics.
"""

from __future__ import annotations

from ..errors import ConfigError

__all__ = ["SCORING", "DEFAULT_SCORING", "SCORING_HELP", "SCORING_SUMMARY", "ignores_zero_marked"]

#: how gt rows marked zero (``consider`` = 0: people outside the annotated area, occluded,
#: flagged as not to be scored) are scored, by name: ``ignore_zero_marked`` of
#: :func:`~motiontrack.evaluate.sequence.preprocess`.
#:
#: ``trackeval``: TrackEval's MOTChallenge convention, the one published results use. The rows
#: are dropped; a tracker box on one is a false positive (with MOTChallenge classes, boxes on
#: distractor classes are removed).
#:
#: ``ignore-regions``: the rows are ignore regions. Each frame, tracker boxes are matched to them
#: (Hungarian on IoU, pairs with IoU >= 0.5) and the matched boxes are removed before scoring, so
#: they count neither as hits nor as false positives; everything else as ``trackeval``.
SCORING: dict[str, bool] = {"trackeval": False, "ignore-regions": True}
DEFAULT_SCORING = "trackeval"

#: the ``--scoring`` help of every command that scores tracks
SCORING_HELP = (
    "how ground-truth rows marked zero (consider = 0) count. trackeval (default): TrackEval's "
    "MOTChallenge convention, comparable with published results; the rows are dropped and a "
    "tracker box on one is a false positive. ignore-regions: the rows are ignore regions; a "
    "tracker box matched to one (IoU >= 0.5) is dropped, neither a hit nor a false positive")

#: what each convention does, in one phrase (the last line of ``motiontrack evaluate``'s table)
SCORING_SUMMARY = {
    "trackeval": "zero-marked gt rows dropped, tracker boxes on them are false positives",
    "ignore-regions": "zero-marked gt rows are ignore regions, tracker boxes on them not counted",
}


def ignores_zero_marked(scoring: str) -> bool:
    """Whether the convention named ``scoring`` treats zero-marked gt rows as ignore regions;
    :class:`ConfigError` naming the valid ones for an unknown name."""
    try:
        return SCORING[scoring]
    except (KeyError, TypeError):
        raise ConfigError(f"unknown scoring {scoring!r}; valid: {', '.join(SCORING)}") from None
