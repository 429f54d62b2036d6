"""Track colours: a track visible in a frame never shares its colour with another visible track.

A colour derived from the id alone (a hash) gives two tracks the same colour as soon as their ids
collide, and with a few dozen ids that happens in most busy frames. :class:`TrackColors` hands out
palette colours instead: a track keeps its colour while it stays visible, gets it back when it
returns unless another visible track holds it, and a new track takes the free colour that has gone
unused longest (so a colour is not reused at once for a different person).

The palette (:func:`palette_color`) is 12 saturated hues, ordered so that consecutive colours are
far apart on the hue circle, then the same hues darker and paler, then hues in between: every index
is a different BGR colour, so there are always enough colours for the tracks of a frame. None of
them is grey or white, the colours of regions and hypotheses.
"""

from __future__ import annotations

from collections import OrderedDict
from functools import lru_cache
from typing import Iterable

import cv2
import numpy as np

__all__ = ["BASE_COLORS", "palette_color", "TrackColors"]

#: saturated hues handed out before any darker or paler one
BASE_COLORS = 12
#: hue steps (OpenCV hue units, 0..179, 15 apart) in the order they are handed out: each next hue is
#: far from the ones before it
_HUE_ORDER = (0, 6, 3, 9, 1, 7, 4, 10, 2, 8, 5, 11)
#: (saturation, value) of each ring of 12 hues: vivid, dark, pale
_SHADES = ((230, 255), (255, 170), (120, 255))


@lru_cache(maxsize=1024)
def palette_color(k: int) -> tuple[int, int, int]:
    """BGR colour number ``k`` (>= 0) of the palette; different ``k`` give different colours."""
    if k < 0:
        raise ValueError(f"palette index must be >= 0, got {k}")
    ring, j = divmod(k, BASE_COLORS)
    sat, val = _SHADES[ring % len(_SHADES)]
    # after the three shades of the 12 hues, shift the hues by 1..14 units (15 is the next step)
    shift = (ring // len(_SHADES)) % 15
    band = ring // (len(_SHADES) * 15)   # beyond 540 colours: lower the value step by step
    hue = (_HUE_ORDER[j] * 15 + shift) % 180
    hsv = np.uint8([[[hue, sat, max(40, val - 10 * band)]]])
    b, g, r = cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0, 0]
    return int(b), int(g), int(r)


class TrackColors:
    """Colours of the tracks of one video, frame by frame (:meth:`assign`).

    Parameters
    ----------
    remember : how many track ids keep their colour while not visible (the least recently shown
        are forgotten first), so memory stays bounded on endless streams.
    """

    def __init__(self, remember: int = 4096) -> None:
        self.remember = remember
        self._index: OrderedDict[int, int] = OrderedDict()   # track id → palette index
        self._shown: set[int] = set()                        # ids visible in the last frame
        self._last: dict[int, int] = {}                      # palette index → last frame shown
        self._frame = 0

    def assign(self, ids: Iterable[int]) -> dict[int, tuple[int, int, int]]:
        """BGR colour of each track visible in the next frame; no two ids get the same colour."""
        self._frame += 1
        ids = list(dict.fromkeys(int(i) for i in ids))
        # tracks visible in the last frame first: their colours were distinct there, so each keeps
        # its own; a returning track gets its old colour back only if it is still free
        order = [i for i in ids if i in self._shown] + [i for i in ids if i not in self._shown]
        taken: dict[int, int] = {}    # palette index → id
        pending = []
        for tid in order:
            k = self._index.get(tid)
            if k is not None and k not in taken:
                taken[k] = tid
            else:
                pending.append(tid)
        for tid in pending:
            k = self._free(taken)
            taken[k] = tid
            self._index[tid] = k
        for k, tid in taken.items():
            self._last[k] = self._frame
            self._index.move_to_end(tid)
        while len(self._index) > self.remember:
            self._index.popitem(last=False)
        self._shown = set(ids)
        return {tid: palette_color(k) for k, tid in taken.items()}

    def _free(self, taken: dict[int, int]) -> int:
        """The palette index not in ``taken`` that has gone unshown longest (never shown first,
        then the lowest index); beyond :data:`BASE_COLORS` only when that many are taken."""
        candidates = (k for k in range(max(BASE_COLORS, len(taken) + 1)) if k not in taken)
        return min(candidates, key=lambda k: (self._last.get(k, 0), k))
