"""Built-in motion detectors: frame differencing, OpenCV background subtractors, the Reading People
Tracker's temporal-median background, and dense optical flow (Farnebäck)."""

from __future__ import annotations

from typing import Any, Callable

import cv2
import numpy as np

from ..config import check_knn_samples
from ..imaging import to_gray
from .base import DETECTORS, MotionDetector
from .hold import Hold
from .shadows import enclosed_shadows

#: the random generator is seeded with ``seed * _SEED_STRIDE + frame``: seeds do not share
#: sequences for videos shorter than this many frames
_SEED_STRIDE = 1_000_003

SHADOW_VALUE = 127  # MOG2/KNN mark shadows with 127; only 255 is foreground


def _absdiff_max(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per-pixel absolute difference, the largest over colour channels: (h, w) uint8."""
    d = cv2.absdiff(a, b)
    return d.max(axis=2) if d.ndim == 3 else d


def binary(fg: np.ndarray) -> np.ndarray:
    """Subtractor output → 0/255 with shadows (127) and soft values dropped."""
    _, out = cv2.threshold(fg, 200, 255, cv2.THRESH_BINARY)
    return out


@DETECTORS.register("frame_diff")
class FrameDiff(MotionDetector):
    """Frame differencing: max over channels of |frame_t − frame_{t−gap}| > threshold.

    A ``gap`` of a few frames makes slow objects show their whole body rather than two thin edges.
    """

    def __init__(self, threshold: int = 25, gap: int = 2) -> None:
        self.threshold = int(threshold)
        self.gap = int(gap)
        self._ring: list[np.ndarray] = []

    def apply(self, image: np.ndarray, protect: np.ndarray | None = None) -> np.ndarray:
        if self._ring and self._ring[0].shape != image.shape:
            self._ring = []
        self._ring.append(image.copy())
        if len(self._ring) > self.gap + 1:
            self._ring.pop(0)
        if len(self._ring) == 1:
            return np.zeros(image.shape[:2], np.uint8)
        diff = _absdiff_max(image, self._ring[0])
        _, mask = cv2.threshold(diff, self.threshold, 255, cv2.THRESH_BINARY)
        return mask

    def relearn(self, image: np.ndarray | None = None) -> None:
        self._ring = [image.copy()] if image is not None else []

    def background(self) -> np.ndarray | None:
        return self._ring[0] if self._ring else None


class _OpenCVSubtractor(MotionDetector):
    """Wraps a ``cv2.BackgroundSubtractor`` that ``make()`` creates; ``learning_rate`` −1 lets
    OpenCV choose."""

    #: times :meth:`relearn` feeds its image to the new model (a model that wants a pixel
    #: stable for some frames before it calls it background: CNT)
    relearn_repeats = 1

    def __init__(self, make: Callable[[], Any], learning_rate: float = -1.0) -> None:
        self._make = make
        self.sub = make()
        self.learning_rate = float(learning_rate)

    def apply(self, image: np.ndarray, protect: np.ndarray | None = None) -> np.ndarray:
        return binary(self.sub.apply(image, learningRate=self.learning_rate))

    def relearn(self, image: np.ndarray | None = None) -> None:
        """A new model from ``make()``, which learns ``image`` first when given."""
        self.sub = self._make()
        self._restart()
        if image is not None:
            for _ in range(self.relearn_repeats):
                self.apply(image)

    def _restart(self) -> None:
        """Reset the wrapper's own per-model state (after a new model)."""


class _SelectiveSubtractor(_OpenCVSubtractor):
    """An OpenCV subtractor with selective update.

    Protected pixels (tracked objects) are fed to the model with its own background values, so
    the model does not learn them; there, foreground is decided by the difference from the
    background image instead (largest channel difference above ``protect_threshold``). The
    background image is refreshed every ``BG_REFRESH`` frames (it changes slowly and costs about
    half a subtractor update to compute).
    """

    BG_REFRESH = 10
    #: the subtractor draws from OpenCV's thread-local random generator (KNN's sample updates)
    uses_rng = False
    seed = 0
    #: times the first frame is learnt before it is classified: a model that needs several
    #: matching samples (KNN) otherwise reports every pixel as foreground for that many frames
    prime = 0

    def __init__(self, make: Callable[[], Any], learning_rate: float = -1.0,
                 protect: bool = False, protect_threshold: int = 30,
                 hold: Hold | None = None, hold_speed: float | None = None,
                 shadow_inside: bool = False) -> None:
        super().__init__(make, learning_rate)
        #: shadow pixels between a region's own foreground above and below are the object's
        self.shadow_inside = bool(shadow_inside)
        self.sideways = False
        #: the model itself does not learn the protected pixels
        self.feeds = bool(protect)
        self.protect_threshold = int(protect_threshold)
        #: the hold (:mod:`.hold`) keeps stopped tracked objects beside the model instead; with
        #: ``protect`` the model keeps them itself and the hold is not used
        self.hold = hold if not self.feeds else None
        # the pipeline passes the boxes (``protect``) and the ghost pixels (``relearn``) to a
        # detector that takes them, a frame ahead in the detector's thread (``relearns``)
        self.protect = self.feeds or self.hold is not None
        self.relearns = self.hold is not None
        if self.hold is not None:
            # a moving object is whole in the model's own mask: only what slows down is held
            self.protect_speed = hold_speed
        self._bg: np.ndarray | None = None
        self._frames = 0
        #: frames of earlier models: the random generator's seeds go on from there
        self._before = 0

    def set_rate(self, fps: float) -> None:
        if self.hold is not None:
            self.hold.fps = float(fps)

    def _restart(self) -> None:
        self._before += self._frames
        self._frames = 0
        self._bg = None
        if self.hold is not None:
            self.hold.reset()

    def apply(self, image: np.ndarray, protect: np.ndarray | None = None,
              relearn: np.ndarray | bool | None = None) -> np.ndarray:
        self._frames += 1
        if self.uses_rng:
            # OpenCV's random generator is per thread and shared with everything else that runs
            # there: seeded per frame, the model's random choices (and so the masks) are the same
            # in whatever thread, and after whatever else, the detector runs.
            cv2.setRNGSeed(self.seed * _SEED_STRIDE + self._before + self._frames)
        if self._frames == 1:
            for _ in range(self.prime):
                self.sub.apply(image, learningRate=self.learning_rate)
        if self.hold is not None:
            raw = self._subtract(image)
            if relearn is True:
                self.hold.reset()
                relearn = None
            return self.hold.apply(image, raw, protect, relearn)
        if not self.feeds or protect is None or self._frames < 3 or not protect.any():
            if self._frames % self.BG_REFRESH == 0:
                self._bg = None
            return binary(self._subtract(image))
        if self._bg is None or self._frames % self.BG_REFRESH == 0 or self._bg.shape != image.shape:
            self._bg = self.sub.getBackgroundImage()
            if self._bg.shape != image.shape:  # gray model on colour input or vice versa
                return binary(self._subtract(image))
        fed = image.copy()
        fed[protect] = self._bg[protect]
        fg = binary(self._subtract(fed))
        diff = _absdiff_max(image, self._bg)
        fg[protect] = np.where(diff[protect] > self.protect_threshold, 255, 0)
        return fg

    def reseed(self, image: np.ndarray, keep: np.ndarray | None = None) -> None:
        """A new model that has learnt ``image``; the hold takes ``image`` as its background
        except at ``keep`` and the pixels it holds."""
        self._before += self._frames
        self.sub = self._make()
        self._bg = None
        for _ in range(self.prime + 1):
            self.sub.apply(image, learningRate=self.learning_rate)
        self._frames = 1
        if self.hold is not None:
            self.hold.reseed(image, keep)

    def _subtract(self, image: np.ndarray) -> np.ndarray:
        """The subtractor's output for ``image`` (0, 127 shadow, 255), the shadow pixels inside
        a region's own foreground made foreground (``shadow_inside``)."""
        raw = self.sub.apply(image, learningRate=self.learning_rate)
        return enclosed_shadows(raw, self.sideways) if self.shadow_inside else raw

    def held(self) -> np.ndarray | None:
        return self.hold.held if self.hold is not None else None

    def background(self) -> np.ndarray | None:
        try:
            bg = self.sub.getBackgroundImage()
        except cv2.error:  # pragma: no cover - some subtractors have none
            return None
        return self.hold.background(bg) if self.hold is not None else bg


@DETECTORS.register("mog2")
class MOG2(_SelectiveSubtractor):
    """Gaussian-mixture background (Zivkovic 2004/2006), OpenCV's MOG2; shadows are not foreground."""

    def __init__(self, history: int = 500, var_threshold: float = 16.0, detect_shadows: bool = True,
                 shadow_threshold: float = 0.5, shadow_inside: bool = True,
                 learning_rate: float = -1.0, protect: bool = False,
                 protect_threshold: int = 30) -> None:
        def make():
            sub = cv2.createBackgroundSubtractorMOG2(int(history), float(var_threshold),
                                                     bool(detect_shadows))
            sub.setShadowThreshold(float(shadow_threshold))
            return sub

        super().__init__(make, learning_rate, protect, protect_threshold,
                         shadow_inside=bool(detect_shadows) and shadow_inside)


@DETECTORS.register("knn")
class KNN(_SelectiveSubtractor):
    """K-nearest-neighbours background (Zivkovic & van der Heijden 2006), OpenCV's KNN."""

    uses_rng = True
    # OpenCV's KNN marks everything foreground until its first samples agree (four frames)
    prime = 4

    def __init__(self, history: int = 500, dist2_threshold: float = 300.0, detect_shadows: bool = True,
                 shadow_threshold: float = 0.5, vehicle_shadow_threshold: float = 0.7,
                 shadow_inside: bool = True, learning_rate: float = -1.0, protect: bool = False,
                 protect_threshold: int = 30, seed: int = 0, n_samples: int = 7,
                 knn_samples: int = 2, hold: bool = True,
                 hold_threshold: int = 30, hold_speed: float = 0.2,
                 accept_s: float = 180.0) -> None:
        check_knn_samples(int(n_samples), int(knn_samples))
        self.seed = int(seed)
        self.thresholds = (float(shadow_threshold), float(vehicle_shadow_threshold))
        self.switches_shadows = bool(detect_shadows) and len(set(self.thresholds)) == 2
        # the threshold a new model starts with; make() must not hold self: a cycle through it
        # would keep each model (megabytes of OpenCV's memory) until a full garbage collection
        self._tau = tau = [self.thresholds[0]]

        def make():
            sub = cv2.createBackgroundSubtractorKNN(int(history), float(dist2_threshold),
                                                    bool(detect_shadows))
            sub.setShadowThreshold(tau[0])
            sub.setNSamples(int(n_samples))
            sub.setkNNSamples(int(knn_samples))
            return sub

        super().__init__(make, learning_rate, protect, protect_threshold,
                         Hold(hold_threshold, accept_s) if hold else None, hold_speed,
                         bool(detect_shadows) and shadow_inside)

    def vehicle_scene(self, vehicles: bool) -> None:
        self.sideways = vehicles
        tau = self.thresholds[vehicles]
        if self.switches_shadows and tau != self._tau[0]:
            self._tau[0] = tau
            self.sub.setShadowThreshold(tau)


@DETECTORS.register("cnt")
class CNT(_OpenCVSubtractor):
    """CNT (counting) background subtractor from opencv-contrib bgsegm: very fast."""

    def __init__(self, min_pixel_stability: int = 15, max_pixel_stability: int = 900,
                 use_history: bool = True, is_parallel: bool = True) -> None:
        self.relearn_repeats = int(min_pixel_stability) + 1
        super().__init__(lambda: cv2.bgsegm.createBackgroundSubtractorCNT(
            int(min_pixel_stability), bool(use_history), int(max_pixel_stability), bool(is_parallel)))


@DETECTORS.register("gsoc")
class GSOC(_OpenCVSubtractor):
    """GSOC background subtractor from opencv-contrib bgsegm (robust, slower; colour input)."""

    wants_color = True

    def __init__(self, n_samples: int = 20, replace_rate: float = 0.003, propagation_rate: float = 0.01,
                 hits_threshold: int = 32) -> None:
        super().__init__(lambda: cv2.bgsegm.createBackgroundSubtractorGSOC(
            nSamples=int(n_samples), replaceRate=float(replace_rate),
            propagationRate=float(propagation_rate), hitsThreshold=int(hits_threshold)))

    def apply(self, image: np.ndarray, protect: np.ndarray | None = None) -> np.ndarray:
        if image.ndim == 2:
            image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
        return binary(self.sub.apply(image))


@DETECTORS.register("mog")
class MOG(_OpenCVSubtractor):
    """Gaussian-mixture background (KaewTraKulPong & Bowden 2001) from bgsegm."""

    def __init__(self) -> None:
        super().__init__(cv2.bgsegm.createBackgroundSubtractorMOG)


@DETECTORS.register("gmg")
class GMG(_OpenCVSubtractor):
    """Bayesian per-pixel background (Godbehere, Matsukawa & Goldberg 2012) from bgsegm."""

    def __init__(self, initialization_frames: int = 20, decision_threshold: float = 0.8) -> None:
        super().__init__(lambda: cv2.bgsegm.createBackgroundSubtractorGMG(
            int(initialization_frames), float(decision_threshold)))


@DETECTORS.register("lsbp")
class LSBP(_OpenCVSubtractor):
    """Local SVD binary pattern background subtractor from bgsegm (slow, robust to illumination)."""

    def __init__(self) -> None:
        super().__init__(cv2.bgsegm.createBackgroundSubtractorLSBP)


@DETECTORS.register("median")
class TemporalMedian(MotionDetector):
    """Temporal-median background, as in the Reading People Tracker's motion detector.

    Every ``update_every`` frames a frame is added to a ring of ``history`` samples and the
    background is their per-pixel median. A pixel is foreground when
    ``|frame − background| / 255 > threshold`` (DETECT_DIFF_THRESH, in [0, 1]). Until the ring
    holds 3 samples the first frame is the background.
    """

    def __init__(self, threshold: float = 0.1, history: int = 25, update_every: int = 5,
                 protect: bool = True) -> None:
        self.protect = bool(protect)
        self.threshold = float(threshold)
        self.history = int(history)
        self.update_every = int(update_every)
        self._ring: np.ndarray | None = None
        self._count = 0
        self._frames = 0
        self._bg: np.ndarray | None = None

    def _add(self, img: np.ndarray) -> None:
        if self._ring is None or self._ring.shape[1:] != img.shape:
            self._ring = np.empty((self.history,) + img.shape, np.uint8)
            self._count = 0
        self._ring[self._count % self.history] = img
        self._count += 1
        n = min(self._count, self.history)
        if n >= 3 or self._bg is None:
            # np.partition is O(n) per pixel; the median is recomputed only when a sample arrives.
            self._bg = np.median(self._ring[:n], axis=0).astype(np.uint8) if n >= 3 else img.copy()

    def apply(self, image: np.ndarray, protect: np.ndarray | None = None) -> np.ndarray:
        if self._frames % self.update_every == 0:
            if protect is not None and self._bg is not None and protect.any() \
                    and self._bg.shape == image.shape:
                # selective update: tracked objects keep the current background in the sample
                sample = image.copy()
                sample[protect] = self._bg[protect]
                self._add(sample)
            else:
                self._add(image)
        self._frames += 1
        diff = _absdiff_max(image, self._bg)
        # threshold in [0, 1] of the 8-bit range; "> t" as the RPT's DETECT_DIFF_THRESH
        _, mask = cv2.threshold(diff, self.threshold * 255.0, 255, cv2.THRESH_BINARY)
        return mask

    def relearn(self, image: np.ndarray | None = None) -> None:
        self._ring = self._bg = None
        self._count = self._frames = 0
        if image is not None:
            self.apply(image)

    def background(self) -> np.ndarray | None:
        return self._bg


@DETECTORS.register("farneback")
class FarnebackMotion(MotionDetector):
    """Dense optical flow (Farnebäck 2003): flow magnitude above a threshold is foreground.

    ``threshold`` is in pixels per frame at processing scale. Useful with a slowly panning camera
    when combined with a high threshold. ``last_flow`` keeps the latest (h, w, 2) flow field."""

    def __init__(self, threshold: float = 0.7, pyr_scale: float = 0.5, levels: int = 3,
                 winsize: int = 15, iterations: int = 3, poly_n: int = 5, poly_sigma: float = 1.1) -> None:
        self.threshold = float(threshold)
        self.args = (float(pyr_scale), int(levels), int(winsize), int(iterations), int(poly_n),
                     float(poly_sigma), 0)
        self._prev: np.ndarray | None = None
        self.last_flow: np.ndarray | None = None
        r = int(winsize) // 2
        self._erode = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1)) if r else None

    def apply(self, image: np.ndarray, protect: np.ndarray | None = None) -> np.ndarray:
        gray = to_gray(image)
        if self._prev is None or self._prev.shape != gray.shape:
            self._prev = gray.copy()
            self.last_flow = np.zeros(gray.shape + (2,), np.float32)
            return np.zeros(gray.shape, np.uint8)
        flow = cv2.calcOpticalFlowFarneback(self._prev, gray, None, *self.args)
        self._prev = gray.copy()
        self.last_flow = flow
        mag = cv2.magnitude(flow[..., 0], flow[..., 1])
        mask = np.where(mag > self.threshold, 255, 0).astype(np.uint8)
        # The flow is smoothed over the averaging window, so moving areas bleed about half a
        # window beyond the object: erode that margin away.
        k = self._erode
        return cv2.erode(mask, k) if k is not None else mask

    def relearn(self, image: np.ndarray | None = None) -> None:
        """Flow is measured between frames: the next one is measured from ``image`` when
        given, else it starts afresh."""
        self._prev = to_gray(image).copy() if image is not None else None
