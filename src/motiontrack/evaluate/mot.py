"""Tracking metrics: CLEAR-MOT, Identity and HOTA, identical to TrackEval.

Every number here reproduces TrackEval (Luiten et al., the reference implementation of the
MOTChallenge benchmark, ``trackeval==1.3.0``) to floating-point rounding; ``tests/golden/`` holds
values produced by TrackEval itself and ``tests/evaluate/test_eval_mot.py`` compares every field to 1e-6.

Pipeline for one sequence (all pure functions, inputs never mutated)::

    gt, pred (Annotations) --preprocess--> SequenceData --clear/identity/hota--> dict of numbers

The families live in modules of their own, each a set of pure functions over one
:class:`~motiontrack.evaluate.sequence.SequenceData`: the box similarity and per-frame pair table
(:mod:`~motiontrack.evaluate.pairs`), the MOTChallenge preprocessing
(:mod:`~motiontrack.evaluate.sequence`), CLEAR-MOT (:mod:`~motiontrack.evaluate.clear`), Identity
(:mod:`~motiontrack.evaluate.identity`) and HOTA (:mod:`~motiontrack.evaluate.hota`). This module
is the front door: every requested family of one sequence, several sequences combined, and the flat
dict of MOTChallenge summary names.

References
----------
* K. Bernardin, R. Stiefelhagen, "Evaluating Multiple Object Tracking Performance: The CLEAR MOT
  Metrics", EURASIP JIVP 2008 (MOTA, MOTP).
* Y. Li, C. Huang, R. Nevatia, "Learning to associate: HybridBoosted multi-target tracker", CVPR 2009
  (MT/PT/ML, Frag).
* E. Ristani et al., "Performance Measures and a Data Set for Multi-Target, Multi-Camera Tracking",
  ECCV-W 2016 (IDF1, IDP, IDR).
* J. Luiten et al., "HOTA: A Higher Order Metric for Evaluating Multi-Object Tracking", IJCV 2021.
"""

from __future__ import annotations

from typing import Iterable, Mapping, Sequence

import numpy as np

from ..errors import ConfigError
from ..types import Annotations
from .clear import clear_metrics, combine_clear
from .framewise import evaluate_framewise
from .hota import combine_hota, hota_metrics
from .identity import combine_identity, identity_metrics
from .sequence import DISTRACTOR_CLASSES, preprocess

__all__ = ["METRIC_FAMILIES", "combine_sequences", "evaluate_sequence", "evaluate_tracking",
           "flatten"]

#: Metric families computed by :func:`evaluate_sequence`.
METRIC_FAMILIES = ("clear", "identity", "hota")


def _check_metrics(metrics: Iterable[str]) -> tuple[str, ...]:
    ms = tuple(m.strip().lower() for m in metrics if m.strip())
    bad = [m for m in ms if m not in METRIC_FAMILIES]
    if bad:
        raise ConfigError(f"unknown metric {bad[0]!r}; valid: {', '.join(METRIC_FAMILIES)}")
    return ms


def evaluate_sequence(
    gt: Annotations,
    pred: Annotations,
    metrics: Iterable[str] = METRIC_FAMILIES,
    threshold: float = 0.5,
    num_timesteps: int | None = None,
    distractor_classes: Sequence[int] = DISTRACTOR_CLASSES,
    do_preproc: bool = True,
    ignore_zero_marked: bool = False,
) -> dict[str, dict]:
    """All requested metric families for one sequence: ``{"clear": {...}, "identity": ..., "hota": ...}``
    with TrackEval's field names."""
    ms = _check_metrics(metrics)
    if not 0.0 < threshold <= 1.0:
        raise ConfigError(f"threshold must be in (0, 1], got {threshold}")
    data = preprocess(gt, pred, num_timesteps, distractor_classes, do_preproc, ignore_zero_marked)
    out: dict[str, dict] = {}
    if "clear" in ms:
        out["clear"] = clear_metrics(data, threshold)
    if "identity" in ms:
        out["identity"] = identity_metrics(data, threshold)
    if "hota" in ms:
        out["hota"] = hota_metrics(data)
    return out


_COMBINERS = {"clear": combine_clear, "identity": combine_identity, "hota": combine_hota}


def combine_sequences(per_sequence: Iterable[Mapping[str, Mapping]]) -> dict[str, dict]:
    """Combine :func:`evaluate_sequence` results of several sequences as TrackEval does."""
    per_sequence = list(per_sequence)
    if not per_sequence:
        return {}
    fams = [k for k in METRIC_FAMILIES if all(k in r for r in per_sequence)]
    return {k: _COMBINERS[k]([r[k] for r in per_sequence]) for k in fams}


def flatten(results: Mapping[str, Mapping]) -> dict[str, float]:
    """A flat dict with the MOTChallenge summary names.

    HOTA, DetA, AssA, LocA, DetRe, DetPr, AssRe, AssPr are the means over the 19 alphas (as
    TrackEval reports them); TP/FP/FN are the CLEAR counts.
    """
    out: dict[str, float] = {}
    h = results.get("hota")
    if h is not None:
        for k in ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr"):
            out[k] = float(np.mean(h[k]))
        out["HOTA(0)"] = float(h["HOTA(0)"])
        out["LocA(0)"] = float(h["LocA(0)"])
    c = results.get("clear")
    if c is not None:
        for k in ("MOTA", "MOTP", "MODA", "sMOTA"):
            out[k] = float(c[k])
        out["recall"] = float(c["CLR_Re"])
        out["precision"] = float(c["CLR_Pr"])
        for k in ("IDSW", "Frag", "MT", "PT", "ML"):
            out[k] = int(c[k])
        out["TP"], out["FP"], out["FN"] = int(c["CLR_TP"]), int(c["CLR_FP"]), int(c["CLR_FN"])
    i = results.get("identity")
    if i is not None:
        for k in ("IDF1", "IDP", "IDR"):
            out[k] = float(i[k])
        for k in ("IDTP", "IDFP", "IDFN"):
            out[k] = int(i[k])
    return out


def evaluate_tracking(
    gt: Annotations,
    pred: Annotations,
    metrics: Iterable[str] = METRIC_FAMILIES,
    threshold: float = 0.5,
    num_timesteps: int | None = None,
    xi: float = 0.75,
    ignore_zero_marked: bool = False,
) -> dict[str, float]:
    """Score one run against ground truth: a flat dict (keys as :func:`flatten`).

    Used by the pipeline to score a run on the fly and by ``motiontrack evaluate``. ``metrics`` may
    also name ``"framewise"``: the ViPER framewise metrics
    (:func:`motiontrack.evaluate.framewise.evaluate_framewise` with localization threshold ``xi``)
    are then merged in under their own keys. ``ignore_zero_marked``: see :func:`preprocess`.
    """
    ms = [m.strip().lower() for m in metrics]
    out = flatten(evaluate_sequence(gt, pred, [m for m in ms if m != "framewise"], threshold,
                                    num_timesteps, ignore_zero_marked=ignore_zero_marked)
                  ) if any(m != "framewise" for m in ms) else {}
    if "framewise" in ms:
        out.update(evaluate_framewise(gt, pred, xi)[0])
    return out
