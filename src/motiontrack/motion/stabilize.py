"""Camera-motion compensation: each frame warped into a reference frame, so that the background
model of a shaking or slowly panning camera sees a steady scene.

The reference (the *anchor*) is one frame. Its corners (``cv2.goodFeaturesToTrack``, Shi-Tomasi)
are followed into every later frame by pyramidal Lucas-Kanade (``cv2.calcOpticalFlowPyrLK``),
starting from where the previous frame's transform puts them, and a similarity transform
(rotation, uniform scale, translation: ``cv2.estimateAffinePartial2D`` with RANSAC) maps the
anchor onto the frame. Measuring every frame against the anchor rather than chaining
frame-to-frame estimates keeps a steady camera's estimate from drifting.

* A transform that moves no corner of the image more than ``min_motion`` pixels is no camera
  motion: the frame is passed on as it is (a fixed camera's masks and tracks are those of the
  pipeline without compensation). A camera found within half of that for 25 frames in a row
  counts as fixed and is measured every 4th frame only, until it moves. Once a frame has moved
  more than ``min_motion``, every frame that moved more than 0.1 px is warped, until 25 frames
  in a row stay within ``min_motion`` (a shaking camera's small shifts are compensated too).
* Otherwise the frame is warped into the anchor's coordinates (:meth:`Stabilizer.apply`) and the
  mask found there is warped back into the frame's (:meth:`Stabilizer.unwarp`): masks, regions
  and tracks stay in the coordinates of the frame the user sees. Anchor pixels the frame does not
  cover keep what the model last saw there and are never foreground.
* When the camera has moved more than ``reanchor`` of the frame's size from the anchor (a pan),
  or the corners can no longer be followed, the current frame becomes the anchor
  (:attr:`StabilizedFrame.reanchored`): the caller moves its background model into the new
  coordinates (:meth:`Stabilizer.to_anchor` of the old model's background image).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import cv2
import numpy as np

from ..config import StabilizeConfig
from ..imaging import to_gray

__all__ = ["Stabilizer", "StabilizedFrame", "compose", "estimate_transform", "corner_shift"]

#: Lucas-Kanade window (px of the measuring image), pyramid levels and iterations: from the
#: previous frame's transform, a 9 px window on 3 levels follows a further shift of about 16 px
#: of the measuring image; the cost grows with window area and iterations (the motion is
#: measured every frame)
_LK = dict(winSize=(9, 9), maxLevel=2,
           criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 0.03))
#: the motion is measured on the gray frame at half the processing scale when its smaller side
#: is at least this (a quarter of the pixels; the corners still sit within a tenth of a pixel)
_HALVE_FROM = 200
#: RANSAC reprojection threshold (px of the measuring image)
_RANSAC_PX = 1.0
_K3 = np.ones((3, 3), np.uint8)
#: frames a flat anchor is kept before the next frame is tried, and frames a lost anchor's last
#: transform is kept before the frame becomes the anchor
_RETRY = 10
#: a camera that stayed within half of ``min_motion`` of the anchor for ``_SETTLED`` measured
#: frames in a row counts as fixed: from then on only every ``_EVERY``-th frame is measured (the
#: others are passed on as they are) until one shows it moving
_SETTLED, _EVERY = 25, 4
#: while the camera moves, frames are warped from this much motion (px) on
_FINE = 0.1
_IDENTITY = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


@dataclass(frozen=True)
class StabilizedFrame:
    """One frame after :meth:`Stabilizer.apply`.

    ``image`` is the frame in the anchor's coordinates (the input itself when not warped);
    ``transform`` the (2, 3) float64 similarity that maps anchor pixels onto the frame's, or
    None when the frame is not warped (the camera has not moved, or the anchor was just taken);
    ``reanchored`` whether the anchor was taken afresh at this frame, and ``previous`` the
    transform from the old anchor onto this frame then (None when it could not be measured);
    ``step`` the (2, 3) camera motion from the previous frame's pixels to this frame's while the
    camera moves (this frame or the previous one moved more than ``min_motion`` from the
    anchor), else None."""

    image: np.ndarray
    transform: np.ndarray | None = None
    reanchored: bool = False
    previous: np.ndarray | None = None
    step: np.ndarray | None = None


def corner_shift(transform: np.ndarray, width: int, height: int) -> float:
    """Largest displacement (px) of the four image corners under ``transform`` (2, 3)."""
    c = np.array([[0, 0], [width, 0], [0, height], [width, height]], float)
    moved = c @ transform[:, :2].T + transform[:, 2]
    return float(np.abs(moved - c).max())


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The (2, 3) transform ``a`` after ``b`` (both (2, 3)): x → a(b(x))."""
    out = a[:, :2] @ b
    out[:, 2] += a[:, 2]
    return out


def estimate_transform(points: np.ndarray, moved: np.ndarray, min_inliers: int
                       ) -> np.ndarray | None:
    """The similarity (2, 3) float64 that maps ``points`` (N, 2) onto ``moved`` (N, 2), fitted
    by RANSAC; None with fewer than ``min_inliers`` inliers (no reliable estimate)."""
    if len(points) < max(min_inliers, 3):
        return None
    m, inliers = cv2.estimateAffinePartial2D(points, moved, method=cv2.RANSAC,
                                             ransacReprojThreshold=_RANSAC_PX, maxIters=200,
                                             refineIters=10)
    if m is None or inliers is None or int(inliers.sum()) < min_inliers:
        return None
    return m


class Stabilizer:
    """Per-frame camera-motion compensation (see the module notes).

    Parameters
    ----------
    cfg : StabilizeConfig
    """

    def __init__(self, cfg: StabilizeConfig) -> None:
        self.cfg = cfg
        self._anchor: np.ndarray | None = None      # the anchor's gray image
        self._shape: tuple[int, int] | None = None  # (h, w) of the frames
        self._factor = 1.0                            # processing px per measuring-image px
        self._lost = 0                                # frames in a row not measured
        self._still = 0                               # measured frames in a row near the anchor
        self._skipped = 0                             # frames passed on unmeasured since then
        self._since = _SETTLED                        # measured frames since one moved
        self._points: np.ndarray | None = None      # (N, 1, 2) float32 corners of the anchor
        self._last = _IDENTITY.copy()                # anchor → previous frame
        self._steady: np.ndarray | None = None      # anchor-coordinates image the model last saw
        #: frames taken as anchors (the first frame included)
        self.anchors = 0

    def reset(self) -> None:
        """Forget the anchor: the next frame is the new one (a source discontinuity)."""
        self._anchor = self._points = self._steady = self._shape = None
        self._last = _IDENTITY.copy()
        self._still = self._skipped = 0
        self._since = _SETTLED

    def apply(self, image: np.ndarray) -> StabilizedFrame:
        """The frame ``image`` ((h, w) or (h, w, 3) uint8, processing scale) in the anchor's
        coordinates."""
        h, w = image.shape[:2]
        if self._anchor is not None and self._shape == (h, w) and self._fixed():
            self._steady = image
            return StabilizedFrame(image)
        gray = self._measuring(image)
        if self._anchor is None or self._shape != (h, w):
            self._take_anchor(gray, image)
            return StabilizedFrame(image)
        m = self._measure(gray)
        if m is None:
            self._still = 0
            return self._unmeasured(gray, image)
        self._lost = 0
        shift = corner_shift(m, w, h)
        self._still = self._still + 1 if shift <= self.cfg.min_motion / 2 else 0
        self._since = 0 if shift > self.cfg.min_motion else self._since + 1
        step = self._step(m, w, h)
        if corner_shift(m, w, h) > self.cfg.reanchor * min(w, h):
            self._take_anchor(gray, image)
            return StabilizedFrame(image, reanchored=True, previous=m, step=step)
        self._last = m
        return dataclasses.replace(self._warp(image, m), step=step)

    def unwarp(self, mask: np.ndarray, frame: StabilizedFrame) -> np.ndarray:
        """``mask`` (h, w uint8, anchor coordinates) in the coordinates of ``frame``'s image, and
        nothing where the anchor's view did not cover the frame; returned as it is when the frame
        was not warped."""
        if frame.transform is None:
            return mask
        h, w = mask.shape[:2]
        out = cv2.warpAffine(mask, frame.transform, (w, h), flags=cv2.INTER_NEAREST,
                             borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        # frame pixels the anchor's view does not reach, a pixel's margin in (interpolation
        # there mixed in the transparent border): the warped frame held stale pixels there
        inside = cv2.warpAffine(np.full((h, w), 255, np.uint8), frame.transform, (w, h),
                                flags=cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT,
                                borderValue=0)
        return cv2.bitwise_and(out, cv2.erode(inside, _K3))

    def to_anchor(self, image: np.ndarray, frame: StabilizedFrame, fill: np.ndarray) -> np.ndarray:
        """``image`` (coordinates of the anchor before ``frame`` re-anchored, e.g. the old
        background model's image) moved into the new anchor's coordinates, over ``fill`` (the new
        anchor frame) where the old anchor did not reach; ``fill`` when the transform between the
        two is unknown."""
        if frame.previous is None or image.shape != fill.shape:
            return fill.copy()
        h, w = fill.shape[:2]
        out = fill.copy()
        # new anchor pixel x shows old-anchor pixel previous^-1(x): map the old image forward
        cv2.warpAffine(image, frame.previous, (w, h), dst=out, flags=cv2.INTER_LINEAR,
                       borderMode=cv2.BORDER_TRANSPARENT)
        return out

    # ---------------------------------------------------------------------------------- steps
    def _fixed(self) -> bool:
        """Whether this frame is passed on unmeasured: the camera counts as fixed and this is
        not one of every ``_EVERY`` frames."""
        if self._still < _SETTLED:
            return False
        self._skipped += 1
        if self._skipped < _EVERY:
            return True
        self._skipped = 0
        return False

    def _unmeasured(self, gray: np.ndarray, image: np.ndarray) -> StabilizedFrame:
        """A frame whose motion could not be measured.

        An anchor with too few corners (a blank or flat picture) cannot be followed: the frame
        is taken as unmoved, and every ``_RETRY`` frames it becomes the anchor instead (the
        model sees the frames unwarped, so nothing is re-learnt). An anchor whose corners are
        lost (the view covered, a jump) keeps the last transform for up to ``_RETRY`` frames;
        then the frame becomes the anchor and the model must re-learn (``previous`` None)."""
        self._lost += 1
        flat = self._points is None or len(self._points) < self.cfg.min_inliers
        if flat:
            if self._lost >= _RETRY:
                self._take_anchor(gray, image)
            self._steady = image
            return StabilizedFrame(image)
        if self._lost >= _RETRY:
            self._take_anchor(gray, image)
            return StabilizedFrame(image, reanchored=True)
        return self._warp(image, self._last)

    def _least(self) -> float:
        """The motion below which a frame is not warped: ``min_motion``, but only ``_FINE``
        while the camera moves (a frame moved more than ``min_motion`` within the last
        ``_SETTLED`` frames), so a shaking camera's small shifts are compensated too."""
        return _FINE if self._since < _SETTLED else self.cfg.min_motion

    def _step(self, m: np.ndarray, w: int, h: int) -> np.ndarray | None:
        """The camera's motion from the previous frame (anchor → it: ``self._last``) to this
        one (anchor → it: ``m``), while the camera moves; None while both stay within
        :meth:`_least` of the anchor (a fixed camera's tracks are left as they are)."""
        least = self._least()
        if corner_shift(m, w, h) <= least and corner_shift(self._last, w, h) <= least:
            return None
        return compose(m, cv2.invertAffineTransform(self._last))

    def _warp(self, image: np.ndarray, m: np.ndarray) -> StabilizedFrame:
        """``image`` warped by ``m`` into the anchor's coordinates."""
        h, w = image.shape[:2]
        if corner_shift(m, w, h) <= self._least():
            self._steady = image
            return StabilizedFrame(image)
        # the frame in anchor coordinates; anchor pixels it does not cover keep what the model
        # saw there last (transparent border), so they never look like a change
        warped = self._steady.copy()
        cv2.warpAffine(image, m, (w, h), dst=warped, flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                       borderMode=cv2.BORDER_TRANSPARENT)
        self._steady = warped
        return StabilizedFrame(warped, m)

    def _measuring(self, image: np.ndarray) -> np.ndarray:
        """The gray image the motion is measured on: ``image`` at ``1 / self._factor``."""
        h, w = image.shape[:2]
        self._factor = 2.0 if min(h, w) >= _HALVE_FROM else 1.0
        gray = to_gray(image)
        if self._factor == 1.0:
            return gray
        return cv2.resize(gray, (w // 2, h // 2), interpolation=cv2.INTER_AREA)

    def _take_anchor(self, gray: np.ndarray, image: np.ndarray) -> None:
        """``gray`` becomes the anchor, with its corners."""
        pts = cv2.goodFeaturesToTrack(gray, maxCorners=self.cfg.features, qualityLevel=0.01,
                                      minDistance=max(3, min(gray.shape) // 30), blockSize=5)
        # corners in processing pixels (the pixel centres of the measuring image scaled up)
        f = self._factor
        self._points = (np.empty((0, 1, 2), np.float32) if pts is None
                        else ((pts + 0.5) * f - 0.5).astype(np.float32))
        self._anchor = gray
        self._shape = image.shape[:2]
        self._last = _IDENTITY.copy()
        self._steady = image
        self._lost = self._still = self._skipped = 0
        self.anchors += 1

    def _measure(self, gray: np.ndarray) -> np.ndarray | None:
        """The transform anchor → ``gray`` (None when the anchor's corners are not followed)."""
        pts = self._points
        if pts is None or len(pts) < self.cfg.min_inliers:
            return None
        f = self._factor
        guess = pts.reshape(-1, 2) @ self._last[:, :2].T + self._last[:, 2]
        # measured in the measuring image's pixels, fitted in processing pixels
        src = ((pts + 0.5) / f - 0.5).astype(np.float32)
        moved, status, _ = cv2.calcOpticalFlowPyrLK(
            self._anchor, gray, src, ((guess + 0.5) / f - 0.5).astype(np.float32).reshape(-1, 1, 2),
            flags=cv2.OPTFLOW_USE_INITIAL_FLOW, **_LK)
        ok = status.ravel() == 1
        return estimate_transform(pts.reshape(-1, 2)[ok],
                                  (moved.reshape(-1, 2)[ok] + 0.5) * f - 0.5,
                                  self.cfg.min_inliers)
