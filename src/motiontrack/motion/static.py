"""Static foreground: objects that stopped recently, from a dual background.

Two background models of the same frames forget at different speeds (Porikli, Ivanov & Haga,
*Robust abandoned object detection using dual foregrounds*, EURASIP JASP 2008):

* the **long-term** background ``B_L`` learns slowly (time constant :attr:`DualBackground.long_s`)
  and only where nothing moves (pixels background in the short-term model), so a person walking
  by never enters it and an object set down stays out of it for tens of seconds;
* the **short-term** background ``B_S`` learns fast (:attr:`DualBackground.short_s`), everywhere,
  so an object that stopped joins it within about a second.

A pixel is foreground in a model where the frame differs from it by more than ``threshold``
levels in some colour channel (colour, because a bag can have the brightness of the ground it
lies on). A pixel foreground in the long-term model and background in the
short-term one is **static foreground**: something that was not there long ago and has not moved
lately. Each pixel counts the frames it has been static foreground (its *evidence*): the count
grows while it is static, holds while something moves over it (foreground in both models: a
passer-by in front of the object), and drops to zero once the pixel matches the long-term
background again (the object was taken away). Pixels whose evidence reaches ``confirm_s`` seconds
form the static mask; its connected components are the :class:`~motiontrack.types.StaticObject`
of the frame, each with its mean difference from the short-term background (``change``: the
noise level for a still object in view).

A component whose outline has its edges in the long-term background rather than in the frame is
a **ghost** (something that stood there when the models started and has left: the frame shows
plain ground) and is left out, with the outline test of :mod:`.ghosts`.

Everything runs on the preprocessed frame (colour or gray, as the motion detector gets it) at
processing scale; docs/analytics.md gives its cost.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..imaging import largest_difference, to_gray
from ..types import Box, StaticFrame, StaticObject
from .ghosts import components, outline_ratio

__all__ = ["DualBackground"]

_K3 = np.ones((3, 3), np.uint8)


class DualBackground:
    """Static foreground of each frame from a long-term and a short-term background.

    Parameters
    ----------
    fps : float
        Frames per second of the source: the time constants are in seconds.
    scale : float
        Processing scale of the frames given to :meth:`apply`: boxes are reported in source
        pixels.
    long_s, short_s : float
        Time constants (seconds) of the long-term and short-term backgrounds.
    threshold : float
        Difference from a background (largest of the colour channels) that makes a pixel
        foreground in it.
    confirm_s : float
        Seconds a pixel must have been static foreground to be in the static mask.
    ghost_ratio : float
        Components whose outline edge strength in the frame over that in the long-term
        background is below this are ghosts and left out (0 = keep all).
    min_pixels : int
        Smallest component (pixels at processing scale) reported.
    """

    def __init__(self, fps: float, scale: float = 1.0, *, long_s: float = 60.0,
                 short_s: float = 0.5, threshold: float = 20.0, confirm_s: float = 0.5,
                 ghost_ratio: float = 0.7, min_pixels: int = 12) -> None:
        fps = float(fps) if fps and fps > 0 else 25.0
        self.fps, self.scale = fps, float(scale)
        self.long_s, self.short_s = float(long_s), float(short_s)
        self.alpha_long = 1.0 - np.exp(-1.0 / (self.long_s * fps))
        self.alpha_short = 1.0 - np.exp(-1.0 / (self.short_s * fps))
        self.threshold = float(threshold)
        self.confirm = max(1, int(round(confirm_s * fps)))
        self.ghost_ratio = float(ghost_ratio)
        self.min_pixels = int(min_pixels)
        # the long-term model learns as a plain mean over its first short_s seconds, so that it
        # holds the scene rather than the first frame's noise
        self._warm = max(1, int(round(self.short_s * fps)))
        self.frames = 0
        self._long: np.ndarray | None = None
        self._short: np.ndarray | None = None
        self._evidence: np.ndarray | None = None

    def apply(self, image: np.ndarray) -> StaticFrame:
        """The static objects of one preprocessed frame (gray or BGR, processing scale); then
        both backgrounds learn the frame."""
        if self._long is None or self._long.shape != image.shape:
            self._long = image.astype(np.float32)
            self._short = self._long.copy()
            self._evidence = np.zeros(image.shape[:2], np.uint16)
            self.frames = 1
            return StaticFrame()
        self.frames += 1
        long8 = cv2.convertScaleAbs(self._long)
        fg_long = largest_difference(image, long8) > self.threshold
        diff_short = largest_difference(image, cv2.convertScaleAbs(self._short))
        fg_short = diff_short > self.threshold
        ev = self._evidence
        np.multiply(ev, fg_long, out=ev)       # the long-term background again: nothing there
        ev += fg_long & ~fg_short & (ev < 65535)
        # learn: the short-term model everywhere, the long-term one only where nothing moves
        cv2.accumulateWeighted(image, self._short, self.alpha_short)
        alpha = max(self.alpha_long, 1.0 / self.frames) if self.frames <= self._warm else self.alpha_long
        cv2.accumulateWeighted(image, self._long, alpha, mask=(~fg_short).view(np.uint8))
        if self.frames <= self._warm:
            return StaticFrame()
        confirmed = (ev >= self.confirm).view(np.uint8) * np.uint8(255)
        confirmed = cv2.morphologyEx(confirmed, cv2.MORPH_OPEN, _K3)
        return StaticFrame(self._objects(image, confirmed, diff_short, long8), confirmed)

    def background(self) -> np.ndarray | None:
        """The long-term background (uint8, processing scale), or None before any frame."""
        return None if self._long is None else cv2.convertScaleAbs(self._long)

    def _objects(self, image: np.ndarray, mask: np.ndarray, diff_short: np.ndarray,
                 long8: np.ndarray) -> tuple[StaticObject, ...]:
        if not cv2.countNonZero(mask):
            return ()
        gray = to_gray(image)
        inv = 1.0 / self.scale
        out = []
        long_gray = None
        for y1, y2, x1, x2, crop in components(mask, self.min_pixels):
            on = crop > 0
            area = int(np.count_nonzero(on))
            if area < self.min_pixels:
                continue
            if self.ghost_ratio > 0:
                if long_gray is None:
                    long_gray = to_gray(long8)
                if outline_ratio(gray[y1:y2, x1:x2], long_gray[y1:y2, x1:x2], crop) < self.ghost_ratio:
                    continue
            # the component's box: its outline's pixels are the mask's, so the crop's box
            bx, by, bw, bh = cv2.boundingRect(crop)
            x, y = x1 + bx, y1 + by
            frames = int(self._evidence[y1:y2, x1:x2][on].max())
            change = float(diff_short[y1:y2, x1:x2][on].mean())
            out.append(StaticObject(Box(x * inv, y * inv, bw * inv, bh * inv),
                                    float(area) * inv * inv, frames, round(change, 2)))
        return tuple(out)
