"""Single-object trackers: follow one object from a given box.

Every tracker in :data:`SINGLE_TRACKERS` has the same interface::

    t = SINGLE_TRACKERS.create("csrt")
    t.init(frame, Box(x, y, w, h))            # frame: (H, W, 3) uint8 BGR
    ok, box, score = t.update(next_frame)      # box: Box | None, score in [0, 1]

Wrapped OpenCV trackers
-----------------------
``csrt`` (Lukežič et al., "Discriminative correlation filter with channel and spatial reliability",
CVPR 2017), ``kcf`` (Henriques et al., "High-speed tracking with kernelized correlation filters",
PAMI 2015), ``mil`` (Babenko et al., "Visual tracking with online multiple instance learning",
CVPR 2009), the legacy ``mosse`` (Bolme et al., "Visual object tracking using adaptive correlation
filters", CVPR 2010) and ``medianflow`` (Kalal et al., "Forward-backward error: automatic detection
of tracking failures", ICPR 2010), and the DNN trackers ``nano`` (NanoTrack; needs the backbone and
neck-head ONNX files) and ``vit`` (needs the ViT tracker ONNX file). Model files are never
downloaded: pass their paths (``backbone=..., neckhead=...`` or ``net=...``).

Our own trackers
----------------
``meanshift`` and ``camshift`` follow the peak of a hue-histogram back-projection
(Bradski, "Computer vision face tracking for use in a perceptual user interface", Intel Technology
Journal 1998; Comaniciu, Ramesh & Meer, "Kernel-based object tracking", PAMI 2003) with
``cv2.meanShift`` / ``cv2.CamShift``. By default the model histogram is the
*background-weighted histogram* of Comaniciu et al. 2003 (sec. 6.1): hue bins that are common in a
ring around the initial box are down-weighted by ``min(1, o* / o_u)``, where ``o_u`` is the
background histogram and ``o*`` its smallest non-zero bin, so the tracker does not drift onto
background of a similar colour.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Callable, Iterator

import cv2
import numpy as np

from ..errors import ConfigError, opencv_reason
from ..registry import Registry
from ..types import Box
from .association import iou_matrix

log = logging.getLogger(__name__)

__all__ = ["SingleTracker", "SINGLE_TRACKERS", "OpenCVTracker", "HistogramTracker",
           "MeanShiftTracker", "CamShiftTracker", "clip_box", "parse_box", "create_single_tracker",
           "follow", "follow_accuracy", "hue_mask", "background_weights"]


def parse_box(text: str) -> Box:
    """``"x,y,w,h"`` (pixels, top-left corner and size) → :class:`Box`.

    Raises
    ------
    ConfigError
        Not four comma-separated numbers, or ``w``/``h`` not positive.
    """
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) != 4:
        raise ConfigError(f"a box must be 'x,y,w,h' (four numbers), got {text!r}")
    try:
        x, y, w, h = (float(p) for p in parts)
    except ValueError:
        raise ConfigError(f"a box must be 'x,y,w,h' (four numbers), got {text!r}") from None
    try:
        return Box(x, y, w, h)
    except ValueError as exc:
        raise ConfigError(f"bad box {text!r}: {exc}") from None


def clip_box(box: Box, width: int, height: int) -> Box | None:
    """The part of ``box`` inside a ``width`` × ``height`` image, or ``None`` if nothing is inside."""
    x1, y1 = max(0.0, box.x), max(0.0, box.y)
    x2, y2 = min(float(width), box.x2), min(float(height), box.y2)
    if x2 - x1 < 1.0 or y2 - y1 < 1.0:
        return None
    return Box(x1, y1, x2 - x1, y2 - y1)


def _as_bgr(frame: np.ndarray) -> np.ndarray:
    if frame.ndim == 2:
        return cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    if frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8:
        return frame
    raise ConfigError(f"expected an (H, W, 3) uint8 BGR or (H, W) gray frame, got shape "
                      f"{frame.shape} dtype {frame.dtype}")


class SingleTracker:
    """Interface: :meth:`init` once from a box, then :meth:`update` on each following frame."""

    name = "?"

    def init(self, frame: np.ndarray, box: Box) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def update(self, frame: np.ndarray) -> tuple[bool, Box | None, float]:  # pragma: no cover
        """Locate the object in ``frame``.

        Returns
        -------
        ok : bool
            False when the tracker reports a failure (then ``box`` is None).
        box : Box or None
            Object box in pixels, clipped to the image.
        score : float
            Confidence in [0, 1] (1.0 for trackers that give none).
        """
        raise NotImplementedError

    def _start(self, frame: np.ndarray, box: Box) -> tuple[np.ndarray, Box]:
        img = _as_bgr(frame)
        h, w = img.shape[:2]
        inside = clip_box(box, w, h)
        if inside is None or inside.w < 4 or inside.h < 4:
            raise ConfigError(f"the initial box {box.x:g},{box.y:g},{box.w:g},{box.h:g} must cover "
                              f"at least 4x4 pixels of the {w}x{h} image")
        self._size = (w, h)
        return img, inside


SINGLE_TRACKERS: Registry[SingleTracker] = Registry("single-object tracker")


# ----------------------------------------------------------------------------- OpenCV wrappers
class OpenCVTracker(SingleTracker):
    """Wrap an OpenCV tracker object (``cv2.Tracker*`` or ``cv2.legacy.Tracker*``).

    Parameters
    ----------
    factory : callable returning a fresh OpenCV tracker.
    legacy : the legacy API (float ``Rect2d`` boxes) instead of the integer ``Rect`` API.
    name : registry name, for messages.
    """

    def __init__(self, factory: Callable[[], Any], legacy: bool = False, name: str = "?",
                 scored: bool = False) -> None:
        self._factory = factory
        self._legacy = legacy
        self._scored = scored
        self.name = name
        self._cv = None

    def init(self, frame: np.ndarray, box: Box) -> None:
        img, b = self._start(frame, box)
        self._cv = self._factory()
        if self._legacy:
            rect = (float(b.x), float(b.y), float(b.w), float(b.h))
        else:
            x, y = int(round(b.x)), int(round(b.y))
            rect = (x, y, max(1, int(round(b.x2)) - x), max(1, int(round(b.y2)) - y))
        try:
            res = self._cv.init(img, rect)
        except cv2.error as exc:  # e.g. MIL on a frame too small for its samples around the box
            h, w = img.shape[:2]
            raise ConfigError(f"the {self.name} tracker cannot start on box "
                              f"{','.join(map(str, rect))} of the {w}x{h} frame (a frame too "
                              f"small for it around the box?): OpenCV says {opencv_reason(exc)}"
                              ) from exc
        if res is False:  # the legacy API returns a bool; the new one returns None
            raise ConfigError(f"{self.name} tracker could not initialise on box {rect}")

    def update(self, frame: np.ndarray) -> tuple[bool, Box | None, float]:
        if self._cv is None:
            raise RuntimeError("call init(frame, box) before update(frame)")
        img = _as_bgr(frame)
        ok, rect = self._cv.update(img)
        if not ok:
            return False, None, 0.0
        x, y, w, h = (float(v) for v in rect)
        if not (np.isfinite([x, y, w, h]).all() and w > 0 and h > 0):
            return False, None, 0.0
        box = clip_box(Box(x, y, w, h), *self._size)
        if box is None:
            return False, None, 0.0
        score = 1.0
        if self._scored:  # only the DNN trackers report a meaningful score
            score = float(np.clip(self._cv.getTrackingScore(), 0.0, 1.0))
        return True, box, score


def _opencv(name: str, create: Callable[[], Any], legacy: bool, doc: str) -> None:
    SINGLE_TRACKERS.register(name, doc)(lambda: OpenCVTracker(create, legacy, name))


_opencv("csrt", lambda: cv2.TrackerCSRT_create(), False,
        "OpenCV CSRT: correlation filter with channel and spatial reliability (accurate, slower)")


@SINGLE_TRACKERS.register("kcf", "OpenCV KCF: kernelized correlation filter (fast; fixed box size)")
def _kcf(detect_thresh: float = 0.3) -> SingleTracker:
    """KCF with failure threshold ``detect_thresh`` on the peak response. OpenCV's default 0.5
    declares failure within a few frames on a narrow walking person whose legs change the
    appearance every frame (synthetic ``walker`` scene); 0.3 keeps following it."""
    if not 0.0 <= float(detect_thresh) <= 1.0:
        raise ConfigError(f"kcf detect_thresh must be in [0, 1], got {detect_thresh}")

    def make():
        p = cv2.TrackerKCF_Params()
        p.detect_thresh = float(detect_thresh)
        return cv2.TrackerKCF_create(p)

    return OpenCVTracker(make, False, "kcf")

_opencv("mil", lambda: cv2.TrackerMIL_create(), False,
        "OpenCV MIL: online multiple-instance learning (fixed box size)")
_opencv("mosse", lambda: cv2.legacy.TrackerMOSSE_create(), True,
        "OpenCV legacy MOSSE: minimum output sum of squared error filter (very fast)")
_opencv("medianflow", lambda: cv2.legacy.TrackerMedianFlow_create(), True,
        "OpenCV legacy MedianFlow: forward-backward Lucas-Kanade points; reports failures")


def _model_file(path: Any, what: str, tracker: str, flag: str) -> str:
    if not path:
        raise ConfigError(f"the {tracker} tracker needs its {what} model file: pass {flag}=PATH "
                          "(ONNX files from the OpenCV model zoo; they are not downloaded)")
    p = Path(path)
    if not p.is_file():
        raise ConfigError(f"{tracker} {what} model file not found: {p}")
    return str(p)


@SINGLE_TRACKERS.register("nano", "OpenCV NanoTrack (DNN); needs backbone=PATH and neckhead=PATH")
def _nano(backbone: str | None = None, neckhead: str | None = None) -> SingleTracker:
    params = cv2.TrackerNano_Params()
    params.backbone = _model_file(backbone, "backbone", "nano", "backbone")
    params.neckhead = _model_file(neckhead, "neck-head", "nano", "neckhead")
    return OpenCVTracker(lambda: cv2.TrackerNano_create(params), False, "nano", scored=True)


@SINGLE_TRACKERS.register("vit", "OpenCV ViT tracker (DNN); needs net=PATH")
def _vit(net: str | None = None) -> SingleTracker:
    params = cv2.TrackerVit_Params()
    params.net = _model_file(net, "network", "vit", "net")
    return OpenCVTracker(lambda: cv2.TrackerVit_create(params), False, "vit", scored=True)


# ------------------------------------------------------------------- hue-histogram trackers
def hue_mask(hsv: np.ndarray, s_min: int, v_min: int, v_max: int) -> np.ndarray:
    """Pixels whose hue is meaningful: saturation ≥ ``s_min`` and ``v_min`` ≤ value ≤ ``v_max``.

    Hue is undefined for grey, very dark and saturated-white pixels (Bradski 1998, sec. 3).
    ``hsv``: (H, W, 3) uint8 OpenCV HSV (hue 0..179) → (H, W) uint8 0/255.
    """
    return cv2.inRange(hsv, (0, int(s_min), int(v_min)), (180, 256, int(v_max)))


def background_weights(obj_hist: np.ndarray, bg_hist: np.ndarray) -> np.ndarray:
    """Background-weighted histogram (Comaniciu, Ramesh & Meer, PAMI 2003, sec. 6.1).

    ``v_u = min(1, o* / o_u)`` with ``o_u`` the background histogram and ``o*`` its smallest
    non-zero bin (``v_u = 1`` where ``o_u = 0``); the model becomes ``obj_hist * v``.

    Parameters
    ----------
    obj_hist, bg_hist : (B,) float
        Object and background histograms over the same bins (any scale).

    Returns
    -------
    (B,) float64, the weighted object histogram (not normalised).
    """
    obj = np.asarray(obj_hist, np.float64).reshape(-1)
    bg = np.asarray(bg_hist, np.float64).reshape(-1)
    nz = bg[bg > 0]
    if nz.size == 0:
        return obj.copy()
    with np.errstate(divide="ignore"):
        v = np.where(bg > 0, np.minimum(1.0, nz.min() / bg), 1.0)
    return obj * v


class HistogramTracker(SingleTracker):
    """Shared part of Mean-Shift and CAMShift: a hue histogram model and its back-projection.

    Parameters
    ----------
    bins : hue histogram bins (OpenCV hue range 0..180).
    s_min, v_min, v_max : hue validity limits, see :func:`hue_mask`.
    background_weighted : use the background-weighted histogram (see module docstring).
    max_iter, eps : mean-shift stopping criteria (iterations, window shift in pixels).
    min_score : below this mean back-projection (0..1) inside the window the object counts as lost.
    """

    def __init__(self, bins: int = 32, s_min: int = 40, v_min: int = 32, v_max: int = 250,
                 background_weighted: bool = True, max_iter: int = 10, eps: float = 1.0,
                 min_score: float = 0.05) -> None:
        if not 2 <= int(bins) <= 180:
            raise ConfigError(f"bins must be in 2..180, got {bins}")
        if not 0.0 <= float(min_score) < 1.0:
            raise ConfigError(f"min_score must be in [0, 1), got {min_score}")
        self.bins = int(bins)
        self.s_min, self.v_min, self.v_max = int(s_min), int(v_min), int(v_max)
        self.background_weighted = bool(background_weighted)
        self.criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, int(max_iter), float(eps))
        self.min_score = float(min_score)
        self.hist: np.ndarray | None = None
        self._window: tuple[int, int, int, int] | None = None

    def _hist(self, hsv: np.ndarray, mask: np.ndarray) -> np.ndarray:
        return cv2.calcHist([hsv], [0], mask, [self.bins], [0, 180]).reshape(-1)

    def init(self, frame: np.ndarray, box: Box) -> None:
        img, b = self._start(frame, box)
        hsv = cv2.cvtColor(img, cv2.COLOR_BGR2HSV)
        valid = hue_mask(hsv, self.s_min, self.v_min, self.v_max)
        x, y = int(round(b.x)), int(round(b.y))
        w, h = max(1, int(round(b.x2)) - x), max(1, int(round(b.y2)) - y)
        inside = np.zeros(valid.shape, np.uint8)
        inside[y:y + h, x:x + w] = 255
        obj = self._hist(hsv, cv2.bitwise_and(valid, inside))
        if obj.sum() < 0.05 * w * h:
            log.warning("%s: few coloured pixels in the box; hue model may be weak", self.name)
            obj = self._hist(hsv, inside)
        if self.background_weighted:
            # a ring one half box-size wide around the object (about 3x its area)
            H, W = valid.shape
            ring = np.zeros(valid.shape, np.uint8)
            ring[max(0, y - h // 2):min(H, y + h + h // 2), max(0, x - w // 2):min(W, x + w + w // 2)] = 255
            ring[y:y + h, x:x + w] = 0
            obj = background_weights(obj, self._hist(hsv, cv2.bitwise_and(valid, ring)))
        peak = obj.max()
        self.hist = (obj * (255.0 / peak) if peak > 0 else obj).astype(np.float32).reshape(-1, 1)
        self._window = (x, y, w, h)
        self._init_size = (w, h)

    def back_projection(self, frame: np.ndarray) -> np.ndarray:
        """(H, W) uint8 likelihood image: the model histogram value of each pixel's hue."""
        if self.hist is None:
            raise RuntimeError("call init(frame, box) before update(frame)")
        hsv = cv2.cvtColor(_as_bgr(frame), cv2.COLOR_BGR2HSV)
        prob = cv2.calcBackProject([hsv], [0], self.hist, [0, 180], 1)
        return cv2.bitwise_and(prob, hue_mask(hsv, self.s_min, self.v_min, self.v_max))

    def _search(self, prob: np.ndarray, window: tuple[int, int, int, int]
                ) -> tuple[int, int, int, int]:  # pragma: no cover - abstract
        raise NotImplementedError

    def update(self, frame: np.ndarray) -> tuple[bool, Box | None, float]:
        prob = self.back_projection(frame)
        window = self._search(prob, self._window)
        x, y, w, h = window
        if w < 2 or h < 2:
            return False, None, 0.0
        score = float(prob[y:y + h, x:x + w].mean()) / 255.0
        box = clip_box(Box(float(x), float(y), float(w), float(h)), *self._size)
        if box is None or score < self.min_score:
            return False, None, score
        self._window = window
        return True, box, score


@SINGLE_TRACKERS.register("meanshift", "Mean-Shift on a hue back-projection (fixed box size; ours)")
class MeanShiftTracker(HistogramTracker):
    """Mean-Shift (Comaniciu et al. 2003) on the hue back-projection; the box keeps its size."""

    name = "meanshift"

    def _search(self, prob, window):
        _, win = cv2.meanShift(prob, window, self.criteria)
        return tuple(int(v) for v in win)


@SINGLE_TRACKERS.register("camshift", "CAMShift on a hue back-projection (adaptive box; ours)")
class CamShiftTracker(HistogramTracker):
    """Continuously Adaptive Mean-Shift (Bradski 1998): the window size follows the object's
    zeroth moment. The returned box is the upright search window; its size is bounded to
    ``[1 / max_growth, max_growth]`` times the initial size so it cannot collapse or swallow
    a background of similar colour."""

    name = "camshift"

    def __init__(self, max_growth: float = 2.0, **kw: Any) -> None:
        super().__init__(**kw)
        if float(max_growth) < 1.0:
            raise ConfigError(f"max_growth must be >= 1, got {max_growth}")
        self.max_growth = float(max_growth)

    def _search(self, prob, window):
        _, win = cv2.CamShift(prob, window, self.criteria)
        x, y, w, h = (int(v) for v in win)
        if w < 2 or h < 2:
            return (x, y, w, h)
        w0, h0 = self._init_size
        g = self.max_growth
        nw = int(np.clip(w, w0 / g, w0 * g))
        nh = int(np.clip(h, h0 / g, h0 * g))
        return (x + (w - nw) // 2, y + (h - nh) // 2, nw, nh)


def create_single_tracker(name: str, **params: Any) -> SingleTracker:
    """``SINGLE_TRACKERS.create(name, **params)`` with bad parameters reported as ConfigError."""
    factory = SINGLE_TRACKERS.get(name)
    try:
        return factory(**params)
    except TypeError as exc:
        raise ConfigError(f"bad parameters for single-object tracker {name!r}: {exc}") from None


def follow(frames: Any, tracker: SingleTracker, box: Box
           ) -> Iterator[tuple[int, np.ndarray, bool, Box | None, float]]:
    """Initialise ``tracker`` on the first frame with ``box``, then update it on every other frame.

    Parameters
    ----------
    frames : iterable of :class:`~motiontrack.types.Frame` (or bare images, numbered from 0).
    tracker : a fresh single-object tracker.
    box : the object's box in the first frame, px.

    Yields
    ------
    (index, image, ok, box, score) per frame; the first frame yields the (clipped) initial box
    with ``ok=True`` and score 1. A tracker that loses the object keeps being updated (some
    recover), yielding ``ok=False, box=None`` meanwhile.
    """
    first = True
    for k, item in enumerate(frames):
        index = int(getattr(item, "index", k))
        image = getattr(item, "image", item)
        if first:
            tracker.init(image, box)
            h, w = image.shape[:2]
            yield index, image, True, clip_box(box, w, h), 1.0
            first = False
            continue
        ok, b, score = tracker.update(image)
        yield index, image, ok, b, score


def follow_accuracy(gt: Any, pred: Any, gt_id: int | None = None) -> dict[str, float]:
    """Per-frame IoU of a single followed object against one ground-truth object.

    Parameters
    ----------
    gt : Annotations, ground truth (1-based frames).
    pred : Annotations, the followed object (one row per frame where the tracker reported a box).
    gt_id : the ground-truth object followed; ``None`` = the gt object with the highest IoU with
        the first predicted box (none when it overlaps no gt box: ``gt_id`` -1, 0 frames).

    Returns
    -------
    dict with ``gt_id``, ``frames`` (frames where the gt object exists, from the first predicted
    frame to the last processed one, i.e. ``pred.meta["last_frame"]`` or the last predicted frame),
    ``mean_iou`` (a missing prediction counts as IoU 0), ``iou50`` (fraction of those frames with
    IoU ≥ 0.5) and ``lost`` (frames without a prediction).
    """
    if len(pred) == 0:
        return {"gt_id": -1.0, "frames": 0.0, "mean_iou": 0.0, "iou50": 0.0, "lost": 0.0}
    f0 = int(pred.frames.min())
    f1 = int(pred.meta.get("last_frame", pred.frames.max()))
    if gt_id is None:
        g0 = gt.at(f0)
        if len(g0) == 0:
            return {"gt_id": -1.0, "frames": 0.0, "mean_iou": 0.0, "iou50": 0.0, "lost": 0.0}
        first = pred.boxes[pred.frames == f0][:1]
        overlap = iou_matrix(first, g0.boxes)[0]
        if overlap.max() <= 0:  # the box given covers no ground-truth object
            return {"gt_id": -1.0, "frames": 0.0, "mean_iou": 0.0, "iou50": 0.0, "lost": 0.0}
        gt_id = int(g0.ids[int(np.argmax(overlap))])
    g = gt.select((gt.ids == gt_id) & (gt.frames >= f0) & (gt.frames <= f1))
    by_frame = {int(f): b for f, b in zip(pred.frames, pred.boxes)}
    ious = np.zeros(len(g))
    lost = 0
    for k, (f, b) in enumerate(zip(g.frames, g.boxes)):
        p = by_frame.get(int(f))
        if p is None:
            lost += 1
            continue
        ious[k] = iou_matrix(p, b)[0, 0]
    n = len(g)
    return {"gt_id": float(gt_id), "frames": float(n),
            "mean_iou": float(ious.mean()) if n else 0.0,
            "iou50": float((ious >= 0.5).mean()) if n else 0.0, "lost": float(lost)}
