"""Ghost regions: foreground left where a still object was learnt into the background and then
moved away (a person standing in the first frames of a video, a car that drives off).

A background subtractor keeps reporting such a place as foreground until its model relearns it,
which takes as long as the object stood there. The test tells the two kinds of region apart by
their outline (the edge-based test used for removed objects in surveillance systems): a real object
has image edges along its outline in the *current* frame, a ghost has them in the *background*
image (where the departed object still is) and none in the current frame, which shows plain
ground there. The score is

    ratio = mean edge(current) / mean edge(background)   over the region's outline pixels

where edge is the local contrast (3×3 maximum − minimum) and the outline is the band of pixels
on both sides of the mask's boundary.
A region whose ratio is below the threshold is a ghost. The background image is our own: a
running average of the gray frames, updated only where the mask is background, so it holds what
the subtractor believes is behind a foreground region.

A ghost still joined to the person who left it (someone standing in the first frame who walks
off) is one region with the person's edges, so the region test keeps it. A pixel-level test
(:meth:`GhostFilter._absorb`) takes such a ghost apart from its border: still pixels that look
like the ground next to them and not like the background held at their place.

The same regions are also tested for light (:func:`lit_share`): a patch of ground the sun or a
lamp brightened shows the background a little brighter at nearly every pixel, where an object
shows its own surface. OpenCV's shadow test already takes ground made darker with its colour
kept; nothing takes ground made brighter, so without this test the sun coming out from behind
a cloud over part of the scene is motion until the model learns it.
"""

from __future__ import annotations

from typing import Callable, Iterator

import cv2
import numpy as np

from ..types import Region
from ..imaging import pixel_window, to_gray

__all__ = ["GhostFilter", "outline_ratio", "edge_strength", "components", "lit_share",
           "lit_on_average"]

#: weight of each new frame in the running background, where the mask is background
RATE = 0.05
#: edge strength (gray levels) added to both means: a region whose outline is flat in both images
#: scores about 1 (kept) instead of a ratio of two noise values
FLAT = 1.0
_K3 = np.ones((3, 3), np.uint8)
#: lowest gain of a lit pixel: light the model calls foreground made the ground at least this
#: much brighter, while the rim of plain ground the mask's clean-up leaves around every object
#: has a gain of about 1
LIT_LOW = 1.02
#: largest difference between a lit pixel's gains in its three colour channels: light scales
#: them alike, a coloured object does not (clothes may be as bright as the ground in gray, not
#: in each channel)
LIT_SPREAD = 0.1
#: offsets of a pixel's 3x3 neighbourhood
_DY, _DX = (a.ravel() for a in np.mgrid[-1:2, -1:2])


def _interior(ys: np.ndarray, xs: np.ndarray, shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The pixels among ``(ys, xs)`` whose whole 3x3 neighbourhood lies in an image of ``shape``."""
    h, w = shape[:2]
    keep = (xs > 0) & (ys > 0) & (xs < w - 1) & (ys < h - 1)
    return ys[keep], xs[keep]


def _still(ys: np.ndarray, xs: np.ndarray, gray: np.ndarray, previous: list[np.ndarray],
           tolerance: int) -> tuple[np.ndarray, np.ndarray]:
    """The pixels among ``(ys, xs)`` whose gray value differs by less than ``tolerance`` from
    their value in each of the ``previous`` frames."""
    v = gray[ys, xs].astype(np.int16)
    keep = np.ones(len(ys), bool)
    for p in previous:
        keep &= np.abs(v - p[ys, xs]) < tolerance
    return ys[keep], xs[keep]


def edge_strength(image: np.ndarray) -> np.ndarray:
    """Morphological gradient (3×3 max − min) of each channel: the local contrast, the height of
    a step edge on both of its sides."""
    return cv2.morphologyEx(image, cv2.MORPH_GRADIENT, _K3)


def outline_ratio(current: np.ndarray, background: np.ndarray, mask: np.ndarray) -> float:
    """Edge strength along the outline of ``mask``'s foreground in ``current`` over the same in
    ``background`` (all three the same (h, w) crop; gray uint8 images, mask 0/255)."""
    # one morphology call for all three: the mask's own gradient is the outline band
    edges = edge_strength(cv2.merge([current, background, mask]))
    cur, bg, _, _ = cv2.mean(edges, mask=cv2.extractChannel(edges, 2))
    return (cur + FLAT) / (bg + FLAT)


def lit_share(current: np.ndarray, background: np.ndarray, mask: np.ndarray, gain: float,
              held: np.ndarray | None = None) -> float:
    """The share of ``mask``'s foreground pixels where ``current`` is ``background`` brightened
    alike in every colour channel, by a factor between :data:`LIT_LOW` and ``gain`` (channels'
    gains within :data:`LIT_SPREAD` of each other). ``current`` and ``background``: the same
    (h, w, 3) crop, uint8 BGR; ``mask``: (h, w) 0/255; ``held``: (h, w) pixels that count as
    not lit whatever they show (those of an object the detector holds)."""
    on = mask > 0
    n = int(np.count_nonzero(on))
    if not n:
        return 0.0
    if held is not None:
        on &= held == 0
    g = (current[on].astype(np.float32) + 1) / (background[on].astype(np.float32) + 1)
    lo, hi = g.min(1), g.max(1)
    return float(np.count_nonzero((lo >= LIT_LOW) & (hi <= gain) & (hi - lo <= LIT_SPREAD))) / n


def lit_on_average(current: np.ndarray, background: np.ndarray, mask: np.ndarray,
                   gain: float) -> bool:
    """Whether the mean colour of ``mask``'s pixels in ``current`` is that of ``background``
    brightened alike in every channel, between :data:`LIT_LOW` and ``gain`` times (the same
    crops as :func:`lit_share`): the light test's first step, at a fraction of its cost."""
    g = np.add(cv2.mean(current, mask=mask)[:3], 1) / np.add(cv2.mean(background, mask=mask)[:3], 1)
    return bool(g.min() >= LIT_LOW and g.max() <= gain and np.ptp(g) <= LIT_SPREAD)


def _component_in(crop: np.ndarray, inner: tuple[int, int, int, int]) -> np.ndarray:
    """The 8-connected component of ``crop`` (uint8 0/255) with the most pixels in its part
    ``inner`` (x1, y1, x2, y2), as a bool mask: the region whose box that part is, not a
    neighbour reaching into the crop's margin."""
    n, labels, _, _ = cv2.connectedComponentsWithStats(crop, connectivity=8)
    if n <= 2:
        return crop > 0
    x1, y1, x2, y2 = inner
    counts = np.bincount(labels[y1:y2, x1:x2].ravel(), minlength=n)
    return labels == 1 + int(np.argmax(counts[1:]))


def components(mask: np.ndarray, min_box: int) -> Iterator[tuple[int, int, int, int, np.ndarray]]:
    """Each outer connected component of ``mask`` (uint8, non-zero set) whose bounding box
    covers at least ``min_box`` pixels: its window ``y1, y2, x1, x2`` (the box grown by 2 px,
    within the image, so that its outline band fits) and the component alone in it (uint8
    0/255: the mask's pixels inside its outer contour). Each is filled in its own window: far
    cheaper than labelling the whole image."""
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    h, w = mask.shape
    for c in contours:
        x, y, bw, bh = cv2.boundingRect(c)
        if bw * bh < min_box:
            continue
        x1, y1 = max(0, x - 2), max(0, y - 2)
        x2, y2 = min(w, x + bw + 2), min(h, y + bh + 2)
        crop = np.zeros((y2 - y1, x2 - x1), np.uint8)
        cv2.drawContours(crop, [c], -1, 255, -1, offset=(-x1, -y1))
        yield y1, y2, x1, x2, cv2.bitwise_and(crop, crop, mask=mask[y1:y2, x1:x2])


class GhostFilter:
    """Finds ghost regions (see the module notes) and keeps them out of the regions.

    A region found to be a ghost is remembered pixel by pixel with the gray value the frame shows
    there (the uncovered ground). On later frames those pixels are taken out of the mask while
    the frame still shows that ground, so a person walking over the ghost is still foreground and
    is not merged with it; a pixel is forgotten once the detector itself calls it background.

    Parameters
    ----------
    ratio : a region whose outline ratio (current / background gradient) is below this is a ghost.
    pixels : also take ghosts apart pixel by pixel from their border (:meth:`_absorb`).
    lit : ``(share, gain)``: a region whose mean colour and at least ``share`` of whose pixels
        show the background brightened by up to ``gain`` (:func:`lit_share`) is light, not an
        object: it is dropped and taken out of the mask (this frame only; ``share`` 0 = off).
        Colour frames only: in gray a coloured object can look like the ground brightened.
    """

    #: gray levels within which a remembered ghost pixel still shows the same ground
    SAME = 20
    #: the background is learnt every this many frames (it only has to follow slow changes)
    EVERY = 4
    #: pixel-level ghost removal (:meth:`_absorb`), run every ``ABSORB_EVERY`` frames: the
    #: previous runs' frames a pixel must match (within ``STILL_T`` gray levels), its largest
    #: difference from its neighbouring ground, the margin by which the background held at its
    #: place must differ more, and the rings of pixels taken per run
    ABSORB_EVERY, STILL, STILL_T, MATCH, MARGIN, STEPS = 3, 2, 8, 10.0, 10.0, 2

    def __init__(self, ratio: float, pixels: bool = True,
                 lit: tuple[float, float] = (0.0, 1.0)) -> None:
        self.ratio = float(ratio)
        self.pixels = bool(pixels)
        self.lit_share, self.lit_gain = float(lit[0]), float(lit[1])
        self.lit = 0           # regions dropped as light
        self._bg: np.ndarray | None = None     # running background (float32 gray)
        self._bg8: np.ndarray | None = None    # the same in uint8
        #: the running background in colour (float32 BGR) and in uint8, for the light test
        self._bgc: np.ndarray | None = None
        self._bgc8: np.ndarray | None = None
        self._ghost: np.ndarray | None = None  # ground seen at remembered ghost pixels, or -1
        #: (y1, y2, x1, x2): every remembered ghost pixel lies in this window (None: none is)
        self._win: tuple[int, int, int, int] | None = None
        self._frames = 0
        self.dropped = 0
        self._prev: list[np.ndarray] = []   # gray frames of the last runs of _absorb

    def regions(self, image: np.ndarray, mask: np.ndarray,
                find: Callable[[np.ndarray], list[Region]], scale: float,
                keep: np.ndarray | None = None) -> tuple[np.ndarray, list[Region]]:
        """``(mask, regions)`` of one frame without its ghosts, then learn the frame's background.

        ``image`` and ``mask`` are at processing resolution (``image`` gray or BGR); ``find``
        turns a mask into regions (boxes in original-frame pixels; ``scale`` converts them).
        ``keep`` (uint8 0/255 or None): pixels the detector holds for a stopped tracked object,
        which differ from the ground it keeps there; they are neither taken nor hidden as ghost
        pixels (a bag of the ground's brightness looks like ground to the gray tests)."""
        self._frames += 1
        gray = None
        if self._bg is None or self._bg.shape != mask.shape:
            self._start(image)
            self._prev = []
            return mask, find(mask)
        detected = mask
        if self._win is not None:
            gray = to_gray(image)
            # forget what the detector no longer reports; hide what still shows the same ground
            # (only inside the window of the remembered pixels: outside it all are forgotten)
            y1, y2, x1, x2 = self._win
            ghost = self._ghost[y1:y2, x1:x2]
            ghost[mask[y1:y2, x1:x2] == 0] = -1
            if keep is not None:
                ghost[keep[y1:y2, x1:x2] > 0] = -1
            remembered = ghost >= 0
            x, y, w, h = cv2.boundingRect(remembered.view(np.uint8))
            self._win = (y1 + y, y1 + y + h, x1 + x, x1 + x + w) if w else None
            same = remembered & (np.abs(gray[y1:y2, x1:x2].astype(np.int16) - ghost) < self.SAME)
            if same.any():
                mask = mask.copy()
                mask[y1:y2, x1:x2][same] = 0
        if self.pixels and self._frames % self.ABSORB_EVERY == 0:
            if gray is None:
                gray = to_gray(image)
            mask = self._absorb(gray, mask, keep)
        regions = find(mask)
        keep_px, keep = keep, []
        for r in regions:
            # two pixels of margin: the outline's outer side and the 3x3 support
            b = (r.box.x, r.box.y, r.box.w, r.box.h)
            x1, y1, x2, y2 = pixel_window(b, scale, mask.shape, margin=2)
            cur = (to_gray(image[y1:y2, x1:x2]) if gray is None  # only the crop is needed
                   else gray[y1:y2, x1:x2])
            crop = mask[y1:y2, x1:x2]
            if outline_ratio(cur, self._bg8[y1:y2, x1:x2], crop) >= self.ratio:
                if self._lit(image, crop, keep_px, (y1, y2, x1, x2)):
                    if mask is detected:
                        mask = mask.copy()
                    bx1, by1, bx2, by2 = pixel_window(b, scale, mask.shape)
                    inner = (bx1 - x1, by1 - y1, bx2 - x1, by2 - y1)
                    mask[y1:y2, x1:x2][_component_in(crop, inner)] = 0
                    self.lit += 1
                else:
                    keep.append(r)
                continue
            self.dropped += 1
            on = crop > 0
            self._ghost[y1:y2, x1:x2][on] = cur[on]
            self._remember(y1, y2, x1, x2)
        if self._frames % self.EVERY == 0:
            # learn where the detector reports background: elsewhere the model still holds
            # whatever was there (a standing person, the object that left a ghost)
            cv2.accumulateWeighted(to_gray(image) if gray is None else gray, self._bg,
                                   1 - (1 - RATE) ** self.EVERY, mask=cv2.bitwise_not(detected))
            self._bg8 = cv2.convertScaleAbs(self._bg)
            if self._bgc is not None:
                cv2.accumulateWeighted(image, self._bgc, 1 - (1 - RATE) ** self.EVERY,
                                       mask=cv2.bitwise_not(detected))
                self._bgc8 = cv2.convertScaleAbs(self._bgc)
        return mask, keep

    def _lit(self, image: np.ndarray, crop: np.ndarray, held: np.ndarray | None,
             window: tuple[int, int, int, int]) -> bool:
        """Whether the region in ``crop`` (the mask in ``window``) is light (see ``lit``): its
        mean colour is the background's brightened alike in every channel, and so are at least
        ``lit_share`` of its pixels. The pixels the detector holds for a stopped object
        (``held``, the whole frame) count as not lit."""
        if self._bgc8 is None or image.ndim != 3:
            return False
        y1, y2, x1, x2 = window
        cur, bg = image[y1:y2, x1:x2], self._bgc8[y1:y2, x1:x2]
        # the means first: they turn away almost every object
        return (lit_on_average(cur, bg, crop, self.lit_gain)
                and lit_share(cur, bg, crop, self.lit_gain,
                              None if held is None else held[y1:y2, x1:x2]) >= self.lit_share)

    def _absorb(self, gray: np.ndarray, mask: np.ndarray,
                keep: np.ndarray | None = None) -> np.ndarray:
        """Pixel-level ghost removal: the mask's border pixels that now look like the ground
        next to them, and not like the background held at their place, are ghost pixels (the
        ground uncovered by an object that stood where the model learnt it). This is the idea
        of ViBe's spatial propagation (Barnich & Van Droogenbroeck 2011), which lets a ghost
        dissolve from its border, applied to our own memory of ghost pixels since OpenCV's
        subtractors cannot be told.

        A border pixel is taken when it matches its value in the frames of the last
        :attr:`STILL` runs (3 and 6 frames ago: a moving object's outline changes), differs from
        the mean of its neighbours outside the mask by less than :attr:`MATCH` gray levels, and
        from the running background by :attr:`MARGIN` more than that. The last test is what
        keeps a person, even one of low contrast: the ground next to a person is also what the
        background holds at the person's place. Up to :attr:`STEPS` rings are taken per run,
        the next ring among the neighbours of the last. Taken pixels join the remembered ghost
        pixels (hidden while they show that ground).

        On PETS a run takes mostly the blurred outline of a ghost still joined to the person
        who left it; that cuts the two apart and the region test then drops the ghost. The
        mask clean-up's dilation leaves a rim of plain ground around every object, which is
        not taken (the background there is ground too), so on a sharp-edged ghost the rim can
        keep the ghost whole until the person has walked clear of it."""
        prev = self._prev
        self._prev = [*prev, gray][-self.STILL:]
        if not prev:
            return mask
        # only a still pixel next to the ground can be taken: the still part of the mask's border
        # (not a pixel the detector holds, nor a ring beyond one: see :meth:`regions`)
        border = cv2.bitwise_and(mask, cv2.bitwise_not(cv2.erode(mask, _K3)))
        if keep is not None:
            border = cv2.bitwise_and(border, cv2.bitwise_not(keep))
        pts = cv2.findNonZero(border)
        if pts is None:
            return mask
        w = mask.shape[1]
        pts = pts.reshape(-1, 2)
        ys, xs = _interior(pts[:, 1], pts[:, 0], mask.shape)
        ys, xs = _still(ys, xs, gray, prev, self.STILL_T)
        out = mask.copy()
        taken = False
        top, bottom, left, right = mask.shape[0], -1, mask.shape[1], -1   # the taken pixels' box
        for _ in range(self.STEPS):
            if not len(ys):
                break
            ny, nx = ys[:, None] + _DY, xs[:, None] + _DX          # (n, 9) neighbourhoods
            ground = out[ny, nx] == 0
            count = ground.sum(1)
            v = gray[ys, xs].astype(np.float32)
            near = np.where(ground, gray[ny, nx], 0).sum(1) / np.maximum(count, 1)
            d = np.abs(v - near)
            ok = (count > 0) & (d < self.MATCH) & (np.abs(v - self._bg[ys, xs]) > d + self.MARGIN)
            if not ok.any():
                break
            ys, xs = ys[ok], xs[ok]
            out[ys, xs] = 0
            self._ghost[ys, xs] = gray[ys, xs]
            taken = True
            top, bottom = min(top, ys.min()), max(bottom, ys.max())
            left, right = min(left, xs.min()), max(right, xs.max())
            # the next ring: still foreground pixels next to the ones just taken
            ny, nx = _interior(ny[ok].ravel(), nx[ok].ravel(), mask.shape)
            flat = np.unique(ny * w + nx)
            ys, xs = flat // w, flat % w
            fg = out[ys, xs] > 0
            if keep is not None:
                fg &= keep[ys, xs] == 0
            ys, xs = _still(ys[fg], xs[fg], gray, prev, self.STILL_T)
        if not taken:
            return mask
        self._remember(int(top), int(bottom) + 1, int(left), int(right) + 1)
        return out

    def seed(self, background: np.ndarray) -> None:
        """The running backgrounds start again from ``background`` (the first background of
        ``motion.bootstrap_s``: gray or BGR, processing scale); remembered ghost pixels are
        forgotten."""
        if self._bg is not None and self._bg.shape == background.shape[:2]:
            self._start(background)

    def _start(self, image: np.ndarray) -> None:
        """The running backgrounds from ``image`` (the colour one for the light test, on colour
        frames), no ghost pixel remembered."""
        gray = to_gray(image)
        self._bg = gray.astype(np.float32)
        self._bg8 = gray.copy()
        colour = self.lit_share > 0 and image.ndim == 3
        self._bgc = image.astype(np.float32) if colour else None
        self._bgc8 = image.copy() if colour else None
        self._ghost = np.full(gray.shape, -1, np.int16)
        self._win = None

    def ghost_pixels(self, shape: tuple[int, int]) -> np.ndarray | None:
        """The remembered ghost pixels (bool, ``shape``: processing scale), or None when there
        are none: a detector that can re-learn them at once makes them background there."""
        if self._win is None or self._ghost is None or self._ghost.shape != shape:
            return None
        y1, y2, x1, x2 = self._win
        out = np.zeros(shape, bool)
        out[y1:y2, x1:x2] = self._ghost[y1:y2, x1:x2] >= 0
        return out

    def _remember(self, y1: int, y2: int, x1: int, x2: int) -> None:
        """Ghost pixels were remembered in the window ``[y1:y2, x1:x2]``."""
        if self._win is not None:
            y1, y2 = min(y1, self._win[0]), max(y2, self._win[1])
            x1, x2 = min(x1, self._win[2]), max(x2, self._win[3])
        self._win = (y1, y2, x1, x2)
