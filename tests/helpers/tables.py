"""Annotations tables built from rows or from a pipeline run."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from motiontrack.types import Annotations, FrameResult


def ann(rows, *, gt: bool = False, **columns) -> Annotations:
    """Annotations from rows laid out as in a MOTChallenge file: ``(frame, id, x, y, w, h)``,
    optionally followed by column 7 (a prediction's score; with ``gt=True`` the ground truth's
    "consider" flag, non-zero = counts) and, for ground truth, column 8 (the class). No rows give
    an empty table. ``columns`` (``consider=``, ``meta=``, ...) go to
    :meth:`Annotations.from_columns` and take precedence over the rows' columns 7 and 8.
    """
    a = np.asarray(rows, dtype=np.float64)
    a = a.reshape(-1, a.shape[-1] if a.size else 6)
    kw = {}
    if a.shape[1] > 6:
        if gt:
            kw["consider"] = a[:, 6] != 0
        else:
            kw["scores"] = a[:, 6]
    if gt and a.shape[1] > 7:
        kw["classes"] = a[:, 7]
    return Annotations.from_columns(a[:, 0], a[:, 1], a[:, 2:6], **{**kw, **columns})


def tracks_of(results: Iterable[FrameResult]) -> Annotations:
    """The tracks of a pipeline run as Annotations: one row ``(frame index + 1, track id, box)``
    per track in each result's ``tracks``, that is what each frame reports as it is processed
    (the backfilled rows of ``FrameResult.earlier`` are left out).

    ``results`` is a run (``motiontrack.track(...)``, ``motiontrack.pipeline.run(...)``: read to
    its end, then closed) or any iterable of :class:`FrameResult`.
    """
    try:
        rows = [(r.index + 1, t.id, *t.box.as_array()) for r in results for t in r.tracks]
    finally:
        close = getattr(results, "close", None)
        if close is not None:
            close()
    return ann(rows)
