"""A sample-based background model with a per-pixel update mask (the ViBe family).

Each pixel keeps ``n_samples`` colour values seen there (Barnich & Van Droogenbroeck, *ViBe: a
universal background subtraction algorithm for video sequences*, IEEE TIP 2011). A pixel is
background when at least ``min_matches`` of its samples lie within ``radius`` levels of the frame
in every colour channel (an L-infinity ball: one ``cv2.inRange`` per sample, on bounds kept
beside the samples). The model learns conservatively: only background pixels learn, each with
probability ``1 / subsampling`` a frame (one of its samples, chosen at random, is replaced by the
frame's value), and as often a background pixel also writes its value into a random sample of a
random 8-neighbour (spatial diffusion: it lets ghosts and dropped objects dissolve from their
border). The random choices are drawn as pixel positions (about ``h * w / subsampling`` a frame),
so an update costs a few thousand writes rather than a pass over the image. A pixel that has been
foreground for ``absorb_s`` seconds learns the frame at every frame until it is background
(about ``min_matches`` frames): what stops and is not protected joins the background.

Unlike OpenCV's subtractors, every call can say where not to learn: ``apply(image, protect)``
with a (h, w) bool mask (the pipeline's boxes of confirmed tracks and static objects). Protected
pixels neither learn nor receive diffused samples, so a person who stops stays foreground. The
protection is bounded: under the mask, ``accept_s`` takes the place of ``absorb_s``, so something
that never moves again (a parked car, a moved chair) becomes background after that time.

``apply(image, relearn=...)`` re-learns at once: ``True`` (a global change, such as a sudden
change of light or a camera that moved) or a (h, w) bool mask of pixels (a ghost: the place an
object left). Re-learnt pixels get every sample from the frame's 3x3 neighbourhood.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..imaging import to_gray
from .base import DETECTORS, MotionDetector
from .ghosts import components, outline_ratio

__all__ = ["SampleBackground"]

#: offsets of the 8-neighbourhood (spatial diffusion)
_NY = np.array([-1, -1, -1, 0, 0, 1, 1, 1])
_NX = np.array([-1, 0, 1, -1, 1, -1, 0, 1])


@DETECTORS.register("vibe")
class SampleBackground(MotionDetector):
    """ViBe-family sample background told where not to learn: people who stop stay foreground.

    See the module notes for the model and its update rule.

    Parameters
    ----------
    n_samples : int
        Samples kept per pixel.
    min_matches : int
        Samples within ``radius`` that make a pixel background (at most ``n_samples``).
    radius : int
        Largest difference (levels, in every colour channel) between the frame and a sample
        that still matches.
    subsampling : int
        A background pixel learns with probability ``1 / subsampling`` a frame, and as often
        diffuses its value to a neighbour.
    protect : bool
        Honour the ``protect`` mask of :meth:`apply` (selective update).
    absorb_s : float
        Seconds a pixel may stay foreground (outside the ``protect`` mask) before it is learnt
        (0 = never: the model then learns only its background and by diffusion).
    accept_s : float
        The same under the ``protect`` mask (0 = never).
    ghost_ratio : float
        Foreground components whose outline edge strength in the frame over that in the model's
        background is below this are ghosts and re-learnt at once (0 = off).
    shadows : bool
        Leave shadows out of the mask (colour input).
    seed : int
        Seed of the random update: a run repeats exactly for a given seed.
    """

    #: the ghost test runs every this many frames, on components of at least this many pixels
    #: (bounding box, processing scale)
    GHOST_EVERY, GHOST_MIN = 4, 48
    #: random update positions drawn in advance, per pixel
    POOL = 4
    #: darkest shadow: the background times this
    SHADOW_TAU = 0.5
    #: largest colour difference from that darker copy, a share of radius
    SHADOW_OFF = 0.5

    def __init__(self, n_samples: int = 8, min_matches: int = 2, radius: int = 20,
                 subsampling: int = 16, protect: bool = True, absorb_s: float = 10.0,
                 accept_s: float = 180.0,
                 ghost_ratio: float = 0.7, shadows: bool = True, seed: int = 0) -> None:
        self.n = int(n_samples)
        self.min_matches = int(min_matches)
        if not 1 <= self.min_matches <= self.n:
            from ..errors import ConfigError
            raise ConfigError(f"motion.vibe.min_matches must be in [1, n_samples={self.n}], "
                              f"got {self.min_matches}")
        self.radius = int(radius)
        self.subsampling = max(1, int(subsampling))
        self.protect = bool(protect)
        self.relearns = True
        self.absorb_s = float(absorb_s)
        self.accept_s = float(accept_s)
        self.ghost_ratio = float(ghost_ratio)
        self.ghosts_dropped = 0
        self.shadows = bool(shadows)
        self.seed = int(seed)
        self.fps = 25.0
        self.reset()

    def set_rate(self, fps: float) -> None:
        """Frames per second of the source: ``accept_s`` is counted in frames of it."""
        self.fps = float(fps) if fps and fps > 0 else 25.0

    def relearn(self, image: np.ndarray | None = None) -> None:
        """Learn the scene afresh (:meth:`MotionDetector.relearn`): every sample from
        ``image`` (a background the caller knows) and its neighbours, or from the next frame."""
        if image is None:
            self.reset()
        else:
            self._init(image)

    def reset(self) -> None:
        """Forget the model: the next frame initialises it again."""
        self._rng = np.random.default_rng(self.seed)
        self._frames = 0
        self._lo: np.ndarray | None = None    # samples - radius, saturated, (n, h, w, c)
        self._hi: np.ndarray | None = None    # samples + radius, saturated
        self._held: np.ndarray | None = None  # frames each pixel has been foreground

    def _due(self, held: np.ndarray, seconds: float) -> np.ndarray:
        """0/255 where ``held`` (frames in the foreground) reached ``seconds`` (none for 0);
        counts stop at 65535 frames (36 minutes at 30 fps), which also ends a longer time."""
        if seconds <= 0:
            return np.zeros_like(held, np.uint8)
        return cv2.compare(held, min(self._frames_of(seconds), 65535), cv2.CMP_GE)

    def _frames_of(self, seconds: float) -> int:
        """``seconds`` in frames of the source (at least 1), or 0 for 0 seconds (never)."""
        return max(1, int(round(seconds * self.fps))) if seconds > 0 else 0

    # -- model state ---------------------------------------------------------------------------
    #
    # The model keeps each sample's bounds (sample -/+ radius, saturated), (n, h*w) items of
    # c bytes each (a numpy void view), so that an update writes whole pixels with one index.

    def _init(self, image: np.ndarray) -> None:
        h, w = image.shape[:2]
        c = 1 if image.ndim == 2 else image.shape[2]
        self._shape = image.shape
        self._lo = np.empty((self.n, h, w, c), np.uint8)
        self._hi = np.empty((self.n, h, w, c), np.uint8)
        lo, hi = self._frame_bounds(image)
        pad_lo = cv2.copyMakeBorder(lo, 1, 1, 1, 1, cv2.BORDER_REPLICATE).reshape(h + 2, w + 2, c)
        pad_hi = cv2.copyMakeBorder(hi, 1, 1, 1, 1, cv2.BORDER_REPLICATE).reshape(h + 2, w + 2, c)
        for k in range(self.n):
            # the first sample is the frame; the others its neighbours (ViBe's initialisation)
            dy, dx = (0, 0) if k == 0 else (int(_NY[k % 8]), int(_NX[k % 8]))
            self._lo[k] = pad_lo[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]
            self._hi[k] = pad_hi[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]
        self._lo_v = _pixels(self._lo)
        self._hi_v = _pixels(self._hi)
        self._held = np.zeros((h, w), np.uint16)
        self._tables(h, w)

    def _tables(self, h: int, w: int) -> None:
        """Random positions for the updates, drawn once (``POOL`` entries per pixel): each frame
        takes a slice at a random start, and turns the sample indices by a random step.
        ``_pos``: pixels; ``_own``: a random sample of that pixel (flat index, sample * npix +
        pixel); ``_nb``: a random sample of a random 8-neighbour of it (``_nb_pixel``)."""
        npix = h * w
        rng = self._rng
        pos = rng.integers(0, npix, self.POOL * npix).astype(np.int32)
        self._pos = pos
        self._own = (rng.integers(0, self.n, len(pos)) * npix + pos).astype(np.int32)
        j = rng.integers(0, 8, len(pos))
        nb = np.clip(pos // w + _NY[j], 0, h - 1) * w + np.clip(pos % w + _NX[j], 0, w - 1)
        self._nb_pixel = nb.astype(np.int32)
        self._nb = (rng.integers(0, self.n, len(pos)) * npix + nb).astype(np.int32)
        self._per_frame = max(1, npix // self.subsampling)

    def _frame_bounds(self, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The frame -/+ radius, saturated (the bounds of a sample taken from it)."""
        r = (float(self.radius),) * 4
        return cv2.subtract(image, r), cv2.add(image, r)

    def _relearn(self, lo: np.ndarray, hi: np.ndarray, where: np.ndarray) -> None:
        """Every sample of the pixels ``where`` (bool (h, w)) from the frame's neighbourhood
        (``lo``, ``hi``: the frame's bounds as void items, (h*w,))."""
        h, w = self._shape[:2]
        ys, xs = np.nonzero(where)
        if not len(ys):
            return
        at = ys * w + xs
        npix = h * w
        for k in range(self.n):
            dy, dx = (0, 0) if k == 0 else (int(_NY[k % 8]), int(_NX[k % 8]))
            src = np.clip(ys + dy, 0, h - 1) * w + np.clip(xs + dx, 0, w - 1)
            self._lo_v[k * npix + at] = lo[src]
            self._hi_v[k * npix + at] = hi[src]
        self._held.reshape(-1)[at] = 0

    # -- per frame -----------------------------------------------------------------------------

    def apply(self, image: np.ndarray, protect: np.ndarray | None = None,
              relearn: bool | np.ndarray | None = None) -> np.ndarray:
        """Foreground mask of ``image`` (0/255 uint8), then the model learns the frame.

        ``protect`` (bool (h, w)): pixels not learnt (with ``self.protect``). ``relearn``:
        ``True`` re-initialises the model from this frame (its mask is then empty); a bool
        (h, w) mask re-learns those pixels from this frame before it is classified.
        """
        if self._lo is None or image.shape != self._shape or relearn is True:
            self._init(image)
            return np.zeros(image.shape[:2], np.uint8)
        lo_img, hi_img = self._frame_bounds(image)
        lo, hi = _pixels(lo_img), _pixels(hi_img)
        if relearn is not None and relearn is not False:
            self._relearn(lo, hi, relearn)
        h, w = image.shape[:2]
        c = 1 if image.ndim == 2 else image.shape[2]
        count = np.zeros((h, w), np.uint8)
        for k in range(self.n):
            m = cv2.inRange(image, self._lo[k], self._hi[k])
            cv2.add(count, m >> 7, dst=count)   # 255 >> 7 = 1
        fg = count < self.min_matches
        self._frames += 1
        if self.ghost_ratio > 0 and self._frames % self.GHOST_EVERY == 0:
            self._drop_ghosts(image, lo, hi, fg)
        self._update(lo, hi, fg.ravel(), protect if self.protect else None)
        out = fg.view(np.uint8) * np.uint8(255)
        if self.shadows and c == 3:
            self._drop_shadows(image, out)
        return out

    def _drop_shadows(self, image: np.ndarray, out: np.ndarray) -> None:
        """Clear the foreground pixels of ``out`` that are shadows: a darker copy of the
        background (first sample) ``a * B`` with ``SHADOW_TAU <= a <= 1`` (as OpenCV's KNN and
        MOG2), within ``radius / 2`` levels in every channel. Shadows are background that is not
        learnt (the model learns only where its own test calls a pixel background)."""
        idx = np.flatnonzero(out)
        if not len(idx):
            return
        npix = out.size
        hi = self._hi[0].reshape(npix, 3)[idx].astype(np.int32)
        v = image.reshape(npix, 3)[idx].astype(np.int32)
        # the background B (first sample) from its bounds: hi - radius unless hi saturated
        b = hi - self.radius
        top = (hi == 255).any(1)
        if top.any():
            b[top] = np.where(hi[top] < 255, b[top],
                              self._lo[0].reshape(npix, 3)[idx[top]] + self.radius)
        dot = np.einsum("ij,ij->i", v, b)
        bb = np.einsum("ij,ij->i", b, b)
        # SHADOW_TAU <= a = dot / bb <= 1, tested in integers first
        cand = np.flatnonzero((dot <= bb) & (dot * 100 >= int(self.SHADOW_TAU * 100) * bb)
                              & (bb > 0))
        if not len(cand):
            return
        a = dot[cand] / bb[cand]
        off = np.abs(v[cand] - a[:, None] * b[cand]).max(1)
        out.reshape(-1)[idx[cand[off <= self.SHADOW_OFF * self.radius]]] = 0

    def _drop_ghosts(self, image: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                     fg: np.ndarray) -> None:
        """Re-learn at once the foreground components (``fg``, bool (h, w), cleared there) that
        are ghosts: their outline has its edges in the model's background and not in the frame
        (the place an object left; :func:`~motiontrack.motion.ghosts.outline_ratio`). Protected
        pixels are tested too: a ghost is never an object to keep."""
        h, w = fg.shape
        for y1, y2, x1, x2, crop in components(fg.view(np.uint8), self.GHOST_MIN):
            bg = self._background(y1, y2, x1, x2)
            if outline_ratio(to_gray(image[y1:y2, x1:x2]), to_gray(bg), crop) < self.ghost_ratio:
                where = np.zeros((h, w), bool)
                where[y1:y2, x1:x2] = crop > 0
                self._relearn(lo, hi, where)
                fg[where] = False
                self.ghosts_dropped += 1

    def _update(self, lo: np.ndarray, hi: np.ndarray, fg: np.ndarray,
                protect: np.ndarray | None) -> None:
        """Learn the frame (bounds ``lo``, ``hi`` as void items) where ``fg`` (flat bool) is
        background and ``protect`` (bool (h, w) or None) does not forbid it."""
        npix = len(fg)
        rng = self._rng
        blocked = fg
        # ``at``: flat sample indices (sample * npix + pixel) written from pixels ``src``
        at: list[np.ndarray] = []
        src: list[np.ndarray] = []
        # foreground for too long (``absorb_s``, or ``accept_s`` under the protect mask):
        # learnt at every frame until background
        fg8 = fg.view(np.uint8).reshape(self._held.shape)
        held = cv2.bitwise_and(self._held, self._held, mask=fg8)   # 0 where background
        cv2.add(held, 1, dst=held, mask=fg8)                        # (saturates at 65535)
        self._held = held
        due8 = self._due(held, self.absorb_s)
        if protect is not None:
            guard = protect.ravel()
            blocked = fg | guard
            inside = np.ascontiguousarray(protect).view(np.uint8) * np.uint8(255)
            late = self._due(held, self.accept_s)
            due8 = cv2.bitwise_or(cv2.bitwise_and(late, inside),
                                  cv2.bitwise_and(due8, cv2.bitwise_not(inside)))
        due = np.flatnonzero(due8) if cv2.countNonZero(due8) else np.empty(0, np.int64)
        at.append((rng.integers(0, self.n, len(due)) * npix + due).astype(np.int32))
        src.append(due.astype(np.int32))
        # random conservative update (about npix / subsampling pixels) and spatial diffusion
        # (as many background pixels write their value into a neighbour's sample): slices of
        # the precomputed random positions at random starts, background pixels only
        m = self._per_frame
        a, b = rng.integers(0, len(self._pos) - m, 2)
        own = self._pos[a:a + m]
        keep = ~blocked[own]
        at.append(self._own[a:a + m][keep])
        src.append(own[keep])
        frm, to = self._pos[b:b + m], self._nb[b:b + m]
        keep = ~blocked[frm]
        if protect is not None:
            keep &= ~guard[self._nb_pixel[b:b + m]]
        at.append(to[keep])
        src.append(frm[keep])
        at, src = np.concatenate(at), np.concatenate(src)
        # the table's sample indices turned by a random step
        at += int(rng.integers(0, self.n)) * npix
        at[at >= self.n * npix] -= self.n * npix
        if len(at):
            self._lo_v[at] = lo[src]
            self._hi_v[at] = hi[src]

    def background(self) -> np.ndarray | None:
        """The first sample of each pixel (uint8, the frame's shape), or None."""
        if self._lo is None:
            return None
        return self._background(0, self._shape[0], 0, self._shape[1])

    def _background(self, y1: int, y2: int, x1: int, x2: int) -> np.ndarray:
        """The first sample of the pixels ``[y1:y2, x1:x2]``, shaped as the frame's crop."""
        lo, hi = self._lo[0, y1:y2, x1:x2], self._hi[0, y1:y2, x1:x2]
        # a sample's upper bound saturates only above 255 - radius, and then its lower one not
        bg = np.where(hi < 255, hi.astype(np.int16) - self.radius, lo.astype(np.int16) + self.radius)
        return bg.astype(np.uint8).reshape((y2 - y1, x2 - x1) + self._shape[2:])


def _pixels(a: np.ndarray) -> np.ndarray:
    """A contiguous uint8 array of pixels (..., c) as a flat array of c-byte void items."""
    c = a.shape[-1] if a.ndim >= 3 else 1
    return np.ascontiguousarray(a).reshape(-1, c).view(f"V{c}").reshape(-1)
