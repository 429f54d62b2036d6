"""HOG people detector: OpenCV's people SVMs, whole frame, motion regions or one box.

Dalal & Triggs, "Histograms of Oriented Gradients for Human Detection", CVPR 2005: a linear SVM
over HOG features of a 64×128 window, shipped with OpenCV as
``cv2.HOGDescriptor_getDefaultPeopleDetector()`` (trained on INRIA Person, where a person is about
96 px tall inside the 128 px window). The window is scanned over an image pyramid
(``detectMultiScale``); overlapping hits are merged here by greedy non-maximum suppression
(:func:`nms`, Felzenszwalb et al. 2010 style: keep the best, drop those overlapping it by more than
``iou_threshold``).

OpenCV also ships the Daimler pedestrian SVM (``cv2.HOGDescriptor_getDaimlerPeopleDetector()``,
``model="daimler"``; Enzweiler & Gavrila, "Monocular Pedestrian Detection: Survey and
Experiments", PAMI 2009): a 48×96 window with the same 16 px blocks, 8 px cells and 9 bins,
trained on small pedestrians in urban video, which suits people a few tens of pixels tall.

People smaller than ~96 px (PETS 2009: ~30×75 px) must be upscaled (``upscale``); restricting the
search to padded crops around motion regions (:meth:`HOGPeopleDetector.detect_in_regions`) or to
one box scaled so that a person of its height fits the window (:meth:`HOGPeopleDetector.people_in_box`)
makes that affordable. Returned boxes are tightened from the window to the person inside it
(``tighten``: the INRIA window has about 16 px of margin above/below and 16 px at each side; the
Daimler window is tightened by the same fractions).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..imaging import to_gray
from ..types import Box, Region

__all__ = ["nms", "HOGParams", "HOGPeopleDetector", "MODELS"]


def _default() -> cv2.HOGDescriptor:
    hog = cv2.HOGDescriptor()   # 64x128, 16 px blocks moved by 8 px, 8 px cells, 9 bins
    hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
    return hog


def _daimler() -> cv2.HOGDescriptor:
    # the same block and cell layout over 48x96 (OpenCV's peopledetect sample builds it so)
    hog = cv2.HOGDescriptor((48, 96), (16, 16), (8, 8), (8, 8), 9)
    hog.setSVMDetector(cv2.HOGDescriptor_getDaimlerPeopleDetector())
    return hog


#: the people SVMs OpenCV ships, by name: their window (width, height) and a descriptor
#: holding the SVM
MODELS = {"default": ((64, 128), _default), "daimler": ((48, 96), _daimler)}


def nms(boxes: np.ndarray, scores: np.ndarray, iou_threshold: float = 0.4) -> np.ndarray:
    """Greedy non-maximum suppression.

    Parameters
    ----------
    boxes : (N, 4) float
        ``x, y, w, h``.
    scores : (N,) float
        Higher is better.
    iou_threshold : float
        A box overlapping an already kept box with IoU above this is dropped.

    Returns
    -------
    (K,) int64
        Indices of the kept boxes, best score first.
    """
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    s = np.asarray(scores, dtype=np.float64).reshape(-1)
    if len(b) != len(s):
        raise ValueError(f"boxes and scores differ in length: {len(b)} vs {len(s)}")
    order = np.argsort(-s, kind="stable")
    x1, y1 = b[:, 0], b[:, 1]
    x2, y2 = b[:, 0] + b[:, 2], b[:, 1] + b[:, 3]
    area = b[:, 2] * b[:, 3]
    keep: list[int] = []
    while len(order):
        i = int(order[0])
        keep.append(i)
        rest = order[1:]
        iw = np.clip(np.minimum(x2[i], x2[rest]) - np.maximum(x1[i], x1[rest]), 0, None)
        ih = np.clip(np.minimum(y2[i], y2[rest]) - np.maximum(y1[i], y1[rest]), 0, None)
        inter = iw * ih
        union = area[i] + area[rest] - inter
        iou = np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)
        order = rest[iou <= iou_threshold]
    return np.asarray(keep, dtype=np.int64)


@dataclass(frozen=True)
class HOGParams:
    """Parameters of :class:`HOGPeopleDetector` (see the module docstring).

    Attributes
    ----------
    upscale : float
        Image magnification before detection (people must be ~96 px tall after it).
    hit_threshold : float
        SVM margin a window needs (``detectMultiScale(hitThreshold=...)``).
    win_stride : int
        Window step in pixels of the magnified image.
    pyramid_scale : float
        Pyramid step (> 1).
    iou_threshold : float
        Non-maximum suppression overlap.
    tighten : bool
        Shrink the 64×128 window to the person inside it (x margin 1/4 of the width on each side,
        y margin 1/8 of the height above and below).
    pad : float
        Regions mode: crop padding as a fraction of the region's height.
    min_crop_height : float
        Regions mode: a crop is at least this tall in original pixels, so that a person split into
        pieces by the motion detector still fits the window.
    model : str
        The SVM (:data:`MODELS`): ``default`` (INRIA, 64×128) or ``daimler`` (48×96).
    fill : float
        Box mode: the share of the window's height that a person as tall as the box fills after
        the crop is magnified (0.85: of 0.75-0.9, the most PETS people found in their boxes with
        both SVMs; the pyramid then also finds people up to the crop's height).
    box_margin : float
        Box mode: crop margin around the box, a fraction of its height on every side.
    """

    upscale: float = 1.0
    hit_threshold: float = 0.0
    win_stride: int = 8
    pyramid_scale: float = 1.05
    iou_threshold: float = 0.4
    tighten: bool = True
    pad: float = 0.3
    min_crop_height: float = 0.0
    model: str = "default"
    fill: float = 0.85
    box_margin: float = 0.15

    def __post_init__(self) -> None:
        if self.model not in MODELS:
            raise ValueError(f"model must be one of {sorted(MODELS)}, got {self.model!r}")
        if not 0.1 <= self.upscale <= 8:
            raise ValueError(f"upscale must be in [0.1, 8], got {self.upscale}")
        if self.win_stride < 1 or self.pyramid_scale <= 1.0:
            raise ValueError("win_stride must be >= 1 and pyramid_scale > 1, got "
                             f"{self.win_stride}, {self.pyramid_scale}")
        if not 0 <= self.iou_threshold <= 1 or self.pad < 0 or self.box_margin < 0:
            raise ValueError("iou_threshold must be in [0, 1], pad and box_margin >= 0")
        if not 0.1 <= self.fill <= 2:
            raise ValueError(f"fill must be in [0.1, 2], got {self.fill}")


class HOGPeopleDetector:
    """Dalal–Triggs people detector with one of OpenCV's people SVMs (``params.model``).

    ``detect(image)`` scans the whole frame; ``detect_in_regions(image, regions)`` scans padded
    crops around motion regions only; ``people_in_box(image, box)`` one crop around a box. All
    return :class:`Region` objects (original-frame pixels) whose ``score`` is the SVM margin,
    after non-maximum suppression.
    """

    def __init__(self, params: HOGParams | None = None) -> None:
        self.params = params or HOGParams()
        window, make = MODELS[self.params.model]
        #: the detection window (width, height) in pixels
        self.WINDOW = window
        self._hog = make()

    # ----------------------------------------------------------------- internals
    def _raw(self, img: np.ndarray, padding: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """Windows ``(K, 4)`` in ``img`` pixels and their scores, before NMS."""
        p = self.params
        if img.shape[0] < self.WINDOW[1] or img.shape[1] < self.WINDOW[0]:
            return np.zeros((0, 4)), np.zeros(0)
        rects, weights = self._hog.detectMultiScale(
            img, hitThreshold=p.hit_threshold, winStride=(p.win_stride, p.win_stride),
            padding=(padding, padding), scale=p.pyramid_scale)
        rects = np.asarray(rects, dtype=np.float64).reshape(-1, 4)
        weights = np.asarray(weights, dtype=np.float64).reshape(-1)
        return rects, weights

    def _tighten(self, b: np.ndarray) -> np.ndarray:
        if not self.params.tighten or len(b) == 0:
            return b
        out = b.copy()
        out[:, 0] += b[:, 2] * 0.25
        out[:, 2] *= 0.5
        out[:, 1] += b[:, 3] * 0.125
        out[:, 3] *= 0.75
        return out

    def _finish(self, boxes: np.ndarray, scores: np.ndarray) -> list[Region]:
        if len(boxes) == 0:
            return []
        keep = nms(boxes, scores, self.params.iou_threshold)
        out = []
        for i in keep:
            x, y, w, h = self._tighten(boxes[i:i + 1])[0]
            if w <= 0 or h <= 0:
                continue
            box = Box(float(x), float(y), float(w), float(h))
            out.append(Region(box=box, centroid=box.center, area=box.area, score=float(scores[i])))
        return out

    # ----------------------------------------------------------------- public
    def detect(self, image: np.ndarray) -> list[Region]:
        """People in the whole frame ``(H, W[, 3]) uint8``; boxes in frame pixels."""
        s = self.params.upscale
        img = to_gray(image)
        if s != 1.0:
            img = cv2.resize(img, None, fx=s, fy=s, interpolation=cv2.INTER_LINEAR)
        b, w = self._raw(img)
        return self._finish(b / s, w)

    def detect_in_regions(self, image: np.ndarray, regions) -> list[Region]:
        """People inside padded crops around ``regions`` (objects with ``.box``, frame pixels).

        Each crop is the region box grown by ``pad × height`` on every side (and to at least
        ``min_crop_height``), magnified so that it is at least one window tall, and scanned alone;
        all hits are merged by one NMS. Regions overlapping each other give overlapping crops;
        NMS removes the duplicates.
        """
        p = self.params
        H, W = image.shape[:2]
        gray = to_gray(image)
        all_b, all_w = [], []
        for r in regions:
            bx = r.box
            pad = p.pad * max(bx.h, 1.0)
            extra = max(0.0, (p.min_crop_height - bx.h - 2 * pad) / 2)
            x1 = int(max(0, np.floor(bx.x - pad - extra / 2)))
            x2 = int(min(W, np.ceil(bx.x2 + pad + extra / 2)))
            y1 = int(max(0, np.floor(bx.y - pad - extra)))
            y2 = int(min(H, np.ceil(bx.y2 + pad + extra)))
            if x2 <= x1 or y2 <= y1:
                continue
            crop = gray[y1:y2, x1:x2]
            s = max(p.upscale, self.WINDOW[1] / crop.shape[0], self.WINDOW[0] / crop.shape[1])
            if s != 1.0:
                crop = cv2.resize(crop, None, fx=s, fy=s, interpolation=cv2.INTER_LINEAR)
            b, w = self._raw(crop)
            if len(b):
                b = b / s
                b[:, 0] += x1
                b[:, 1] += y1
                all_b.append(b)
                all_w.append(w)
        if not all_b:
            return []
        return self._finish(np.concatenate(all_b), np.concatenate(all_w))

    def people_in_box(self, image: np.ndarray, box, scale: float = 1.0) -> list[Region]:
        """People about as tall as ``box`` around it: one crop, one short pyramid.

        Parameters
        ----------
        image : (H, W[, 3]) uint8
            The frame at ``scale`` of the original frame (the pipeline's processing scale).
        box : (4,) float
            ``x, y, w, h`` in original-frame pixels.
        scale : float
            Size of ``image`` relative to the original frame.

        Returns
        -------
        list of Region
            Original-frame pixels. The crop is the box grown by ``box_margin × h`` on every side
            (and to at least one window step around a window), magnified so that a person of the box's height fills
            ``fill`` of the window's height; the pyramid shrinks it from there, so people from
            about the box's height up to the crop's are found, none much shorter.
        """
        p = self.params
        x, y, w, h = (float(v) * scale for v in box)
        ww, wh = self.WINDOW
        if w <= 0 or h <= 0:
            return []
        f = wh * p.fill / h
        # at least one window step around a window centred on the box, each way: a crop of
        # just one window finds only a person centred in it to the pixel
        half_h = max(h * (0.5 + p.box_margin), (wh / 2 + p.win_stride) / f)
        half_w = max(w / 2 + p.box_margin * h, (ww / 2 + p.win_stride) / f)
        cx, cy = x + w / 2, y + h / 2
        H, W = image.shape[:2]
        x1, x2 = int(max(0, cx - half_w)), int(min(W, math.ceil(cx + half_w)))
        y1, y2 = int(max(0, cy - half_h)), int(min(H, math.ceil(cy + half_h)))
        if x2 <= x1 or y2 <= y1:
            return []
        crop = cv2.resize(to_gray(image[y1:y2, x1:x2]), None, fx=f, fy=f,
                          interpolation=cv2.INTER_LINEAR)
        # a box cut by the frame's border: the edge rows repeated up to one window
        short_y, short_x = max(0, wh - crop.shape[0]), max(0, ww - crop.shape[1])
        if short_y or short_x:
            crop = cv2.copyMakeBorder(crop, 0, short_y, 0, short_x, cv2.BORDER_REPLICATE)
        b, score = self._raw(crop, padding=0)
        if len(b):
            b = b / f
            b[:, 0] += x1
            b[:, 1] += y1
            b /= scale
        return self._finish(b, score)
