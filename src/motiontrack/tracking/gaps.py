"""Offline gap filling: a track's box over the frames it was not reported, by interpolation.

An online tracker reports a track only in the frames where a measurement matched it: a person
missed by the detector for a few frames (a weak detection, a short occlusion) is a run of misses
in the tracks file even though the track kept its identity across the gap. Once the run is over
both ends of every gap are known, and the box in between is well estimated by interpolating
linearly between the last box before and the first box after, frame by frame. This is the
post-processing used by most MOTChallenge trackers (e.g. ByteTrack's linear interpolation); it
only adds rows inside a track's own span, so it never joins two identities and never extends a
track past its ends.

Filled rows carry the interpolated confidence and visibility ``-1``; their world position is
left unknown (``-1``): a linear path in the image is not a linear path on the ground, so a
caller with a camera model computes it from the filled box.
"""

from __future__ import annotations

import numpy as np

from ..types import Annotations

__all__ = ["fill_gaps"]


def fill_gaps(tracks: Annotations, max_gap: int) -> Annotations:
    """``tracks`` with every gap of at most ``max_gap`` missing frames filled by interpolation.

    A gap is a run of frames between two consecutive rows of the same id (rows with id < 0,
    anonymous detections, are left alone). Gaps longer than ``max_gap`` stay gaps. When rows are
    added the result is a new table sorted by frame, then id; with nothing to fill (``max_gap``
    <= 0, or no gap that short) it is ``tracks`` itself, in its own order.
    """
    if max_gap <= 0 or len(tracks) < 2:
        return tracks
    order = np.lexsort((tracks.frames, tracks.ids))
    f, i = tracks.frames[order], tracks.ids[order]
    step = np.diff(f)
    gap = (i[1:] == i[:-1]) & (i[1:] >= 0) & (step > 1) & (step <= max_gap + 1)
    if not gap.any():
        return tracks
    starts = np.flatnonzero(gap)                 # the row before each gap (in ``order``)
    missing = step[starts] - 1                   # frames missing in each gap
    a = np.repeat(starts, missing)               # row before, per filled frame
    k = np.arange(missing.sum()) - np.repeat(np.cumsum(missing) - missing, missing) + 1
    t = (k / np.repeat(step[starts], missing))[:, None]   # 0 < t < 1 along the gap

    def lerp(col: np.ndarray) -> np.ndarray:
        c = col[order]
        c0, c1 = c[a], c[a + 1]
        return c0 + (c1 - c0) * (t if c.ndim > 1 else t[:, 0])

    filled = Annotations.from_columns(
        f[a] + k, i[a], lerp(tracks.boxes), scores=lerp(tracks.scores),
        consider=tracks.consider[order][a], classes=tracks.classes[order][a])
    return tracks.concat(filled).sorted()
