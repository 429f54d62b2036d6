"""Motion-mask metrics with the CDnet 2014 rules (changedetection.net).

Ground-truth labels (8-bit grey levels)::

    0 static   50 hard shadow   85 outside the region of interest   170 unknown   255 motion

Counting rules (those of the official CDnet comparator, ``Comparator.cpp`` of the CDnet 2012/2014
utilities by N. Goyette, University of Sherbrooke):

* A pixel counts only when it lies inside the spatial ROI (``ROI.bmp`` non-zero), its ground truth
  is not *unknown* (170), and its frame lies in the temporal ROI (``temporalROI.txt``: first and
  last frame number, inclusive).
* Ground truth 255 is positive; **every other counted label is negative, shadow (50) included**: a
  detection on a shadow pixel is a false positive and no detection there a true negative. The
  comparator additionally counts ``shadow_errors`` (shadow pixels detected as motion) from which
  the server computes FPR-S; we report it too.
* Outside-ROI (85) pixels are excluded. The official comparator excludes them only through
  ``ROI.bmp`` (which is black exactly where the ground truth says 85); we exclude both, so a
  missing ``ROI.bmp`` still gives CDnet's numbers.
* A prediction pixel is foreground when it equals 255 (CDnet's binary masks are 0/255; the
  comparator tests ``== WHITE``). Any other value — e.g. the 127 that OpenCV's MOG2/KNN write for
  shadows — is background. Boolean masks: ``True`` is foreground.

Metrics (Goyette et al., "changedetection.net: A new change detection benchmark dataset",
CVPR Workshops 2012, §4; Wang et al., "CDnet 2014: An expanded change detection benchmark dataset",
CVPR Workshops 2014)::

    Recall      = TP / (TP + FN)            Specificity = TN / (TN + FP)
    FPR         = FP / (FP + TN)            FNR         = FN / (TP + FN)
    PWC         = 100 (FN + FP) / (TP + FN + FP + TN)
    Precision   = TP / (TP + FP)            F-measure   = 2 Precision Recall / (Precision + Recall)

A video's metrics come from the counts summed over all its frames (as ``Stats.py`` does for one
video). A ratio with a zero denominator is ``nan``.
"""

from __future__ import annotations

import logging
import math
import re
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Iterable, Iterator, Mapping

import cv2
import numpy as np

from ..errors import InputError
from ..io.imagesize import DEFAULT_MAX_PIXELS, check_image

__all__ = [
    "STATIC", "SHADOW", "OUTSIDE_ROI", "UNKNOWN", "MOTION",
    "MaskCounts", "compare_masks", "mask_metrics", "read_temporal_roi", "read_roi", "read_mask",
    "find_frames", "CDnetVideo", "cdnet_video", "evaluate_masks", "evaluate_mask_folders",
    "MaskEvaluation", "METRIC_NAMES",
]

log = logging.getLogger(__name__)

STATIC, SHADOW, OUTSIDE_ROI, UNKNOWN, MOTION = 0, 50, 85, 170, 255
METRIC_NAMES = ("recall", "specificity", "fpr", "fnr", "pwc", "precision", "f_measure")


@dataclass(frozen=True)
class MaskCounts:
    """Pixel confusion counts (CDnet's ``cm`` line) and how many frames they cover.

    Attributes
    ----------
    tp, fp, fn, tn : int
        True/false positives/negatives, pixels.
    shadow_errors : int
        Shadow (50) ground-truth pixels detected as motion (also counted in ``fp``).
    shadow : int
        Counted shadow ground-truth pixels (the denominator of FPR-S).
    frames : int
        Number of frame pairs summed.
    """

    tp: int = 0
    fp: int = 0
    fn: int = 0
    tn: int = 0
    shadow_errors: int = 0
    shadow: int = 0
    frames: int = 0

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise ValueError(f"{f.name} must be a non-negative integer, got {v!r}")
            object.__setattr__(self, f.name, int(v))

    def __add__(self, other: "MaskCounts") -> "MaskCounts":
        if not isinstance(other, MaskCounts):
            return NotImplemented
        return MaskCounts(**{f.name: getattr(self, f.name) + getattr(other, f.name)
                             for f in fields(self)})

    def as_dict(self) -> dict[str, int]:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    def metrics(self) -> dict[str, float]:
        return mask_metrics(self)


def _ratio(num: float, den: float) -> float:
    return num / den if den else math.nan


def mask_metrics(c: MaskCounts) -> dict[str, float]:
    """The seven CDnet metrics (and FPR-S) from summed counts; ``nan`` for 0/0.

    Returns keys ``recall, specificity, fpr, fnr, pwc`` (percent), ``precision, f_measure,
    fpr_shadow``.
    """
    recall = _ratio(c.tp, c.tp + c.fn)
    precision = _ratio(c.tp, c.tp + c.fp)
    if math.isnan(recall) or math.isnan(precision):
        f = math.nan
    else:
        f = _ratio(2.0 * precision * recall, precision + recall)
    return {
        "recall": recall,
        "specificity": _ratio(c.tn, c.tn + c.fp),
        "fpr": _ratio(c.fp, c.fp + c.tn),
        "fnr": _ratio(c.fn, c.tp + c.fn),
        "pwc": _ratio(100.0 * (c.fn + c.fp), c.tp + c.fn + c.fp + c.tn),
        "precision": precision,
        "f_measure": f,
        "fpr_shadow": _ratio(c.shadow_errors, c.shadow),
    }


def compare_masks(gt: np.ndarray, pred: np.ndarray, roi: np.ndarray | None = None) -> MaskCounts:
    """Confusion counts of one predicted mask against one CDnet ground truth (pure, vectorised).

    Parameters
    ----------
    gt : (H, W) uint8
        CDnet labels (0, 50, 85, 170, 255); other grey levels count as negatives, as in CDnet.
        A stack ``(T, H, W)`` works too and sums over ``T`` (``frames`` = T).
    pred : (H, W) or (T, H, W), uint8 (foreground = 255) or bool (foreground = True)
    roi : (H, W) array or None
        Spatial ROI: non-zero = inside. ``None``: the whole image.

    Returns
    -------
    MaskCounts
    """
    gt = np.asarray(gt)
    pred = np.asarray(pred)
    if gt.shape != pred.shape:
        raise ValueError(f"ground truth and prediction must have the same shape, got {gt.shape} "
                         f"and {pred.shape}")
    if gt.ndim not in (2, 3):
        raise ValueError(f"masks must be (H, W) or (T, H, W), got shape {gt.shape}")
    fg = pred if pred.dtype == bool else (pred == MOTION)
    valid = (gt != UNKNOWN) & (gt != OUTSIDE_ROI)
    if roi is not None:
        roi = np.asarray(roi)
        if roi.shape != gt.shape[-2:]:
            raise ValueError(f"ROI shape {roi.shape} differs from the mask shape {gt.shape[-2:]}")
        valid &= roi != 0
    pos = gt == MOTION
    # code 0 = TN, 1 = FP, 2 = FN, 3 = TP over the counted pixels
    code = (pos.astype(np.uint8) << 1) | fg.astype(np.uint8)
    tn, fp, fn, tp = np.bincount(code[valid], minlength=4)[:4]
    shadow = valid & (gt == SHADOW)
    return MaskCounts(tp=int(tp), fp=int(fp), fn=int(fn), tn=int(tn),
                      shadow_errors=int(np.count_nonzero(shadow & fg)),
                      shadow=int(np.count_nonzero(shadow)),
                      frames=gt.shape[0] if gt.ndim == 3 else 1)


# ---------------------------------------------------------------------------------------------
# Files
# ---------------------------------------------------------------------------------------------


def read_temporal_roi(path: str | Path) -> tuple[int, int]:
    """``temporalROI.txt`` → ``(first, last)`` frame numbers (inclusive, 1-based as in the file
    names ``gt000470.png``)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"temporal ROI file not found: {p}")
    parts = p.read_text(encoding="utf-8", errors="replace").split()
    try:
        first, last = (int(v) for v in parts[:2])
    except ValueError:
        raise InputError(f"{p}:1: expected two frame numbers 'first last', got "
                         f"{' '.join(parts)[:60]!r}") from None
    if not 0 <= first <= last:
        raise InputError(f"{p}:1: expected 0 <= first <= last, got {first} {last}")
    return first, last


def read_mask(path: str | Path, max_pixels: int = DEFAULT_MAX_PIXELS) -> np.ndarray:
    """An 8-bit single-channel mask ``(H, W) uint8`` (colour files are converted to grey); a file
    whose header claims more than ``max_pixels`` is refused undecoded."""
    p = Path(path)
    check_image(p, max_pixels, "--max-pixels N")
    img = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
    if img is None:
        raise InputError(f"cannot read mask image {p}")
    return img


def read_roi(path: str | Path, max_pixels: int = DEFAULT_MAX_PIXELS) -> np.ndarray:
    """``ROI.bmp`` → ``(H, W) bool`` (non-zero = inside)."""
    return read_mask(path, max_pixels) != 0


_NUM_RE = re.compile(r"(\d+)(?=\.[A-Za-z0-9]+$)")
_IMAGE_EXT = {".png", ".bmp", ".jpg", ".jpeg", ".tif", ".tiff", ".pgm", ".ppm", ".pbm"}


def find_frames(folder: str | Path, prefix: str | None = None) -> dict[int, Path]:
    """Image files of a folder by frame number: the digits right before the extension
    (``gt000470.png``, ``bin000470.png``, ``mask_470.png`` → 470).

    Parameters
    ----------
    prefix : only names starting with it (e.g. ``"bin"``); ``None`` = any.

    Raises :class:`InputError` when the folder is missing or two files share a frame number.
    """
    d = Path(folder)
    if not d.is_dir():
        raise InputError(f"mask folder not found: {d}")
    out: dict[int, Path] = {}
    for p in sorted(d.iterdir()):
        if p.suffix.lower() not in _IMAGE_EXT or not p.is_file():
            continue
        if prefix is not None and not p.name.startswith(prefix):
            continue
        m = _NUM_RE.search(p.name)
        if not m:
            continue
        n = int(m.group(1))
        if n in out:
            raise InputError(f"{d}: two masks for frame {n}: {out[n].name} and {p.name}")
        out[n] = p
    return out


@dataclass(frozen=True)
class CDnetVideo:
    """The files of one CDnet video (category folder such as ``baseline/highway``)."""

    root: Path
    inputs: Mapping[int, Path]
    groundtruth: Mapping[int, Path]
    roi: Path | None
    temporal_roi: tuple[int, int] | None


def cdnet_video(folder: str | Path) -> CDnetVideo:
    """Index a CDnet video folder: ``input/in%06d.jpg``, ``groundtruth/gt%06d.png``, ``ROI.bmp``,
    ``temporalROI.txt`` (the last two optional)."""
    root = Path(folder)
    if not (root / "groundtruth").is_dir():
        raise InputError(f"{root}: not a CDnet video folder (no groundtruth/ sub-folder)")
    inputs = find_frames(root / "input", "in") if (root / "input").is_dir() else {}
    roi = root / "ROI.bmp"
    troi = root / "temporalROI.txt"
    return CDnetVideo(root=root, inputs=inputs, groundtruth=find_frames(root / "groundtruth", "gt"),
                      roi=roi if roi.is_file() else None,
                      temporal_roi=read_temporal_roi(troi) if troi.is_file() else None)


@dataclass(frozen=True)
class MaskEvaluation:
    """Result of :func:`evaluate_masks`: summed counts, metrics and per-frame counts."""

    counts: MaskCounts
    metrics: Mapping[str, float]
    per_frame: Mapping[int, MaskCounts]

    def as_dict(self) -> dict[str, float]:
        """Flat dict: counts then metrics (for JSON)."""
        return {**self.counts.as_dict(), **self.metrics}


def evaluate_masks(pairs: Iterable[tuple[int, np.ndarray, np.ndarray]],
                   roi: np.ndarray | None = None) -> MaskEvaluation:
    """Sum :func:`compare_masks` over ``(frame, gt, pred)`` triples."""
    total = MaskCounts()
    per_frame: dict[int, MaskCounts] = {}
    for frame, gt, pred in pairs:
        c = compare_masks(gt, pred, roi)
        per_frame[int(frame)] = c
        total = total + c
    return MaskEvaluation(counts=total, metrics=mask_metrics(total), per_frame=per_frame)


def evaluate_mask_folders(gt_dir: str | Path, pred_dir: str | Path,
                          roi: str | Path | np.ndarray | None = None,
                          temporal_roi: str | Path | tuple[int, int] | None = None,
                          frames: tuple[int, int] | None = None,
                          pred_prefix: str | None = None,
                          max_pixels: int = DEFAULT_MAX_PIXELS) -> MaskEvaluation:
    """Evaluate a folder of predicted masks against a CDnet ground-truth folder.

    Parameters
    ----------
    gt_dir : the ``groundtruth`` folder (or the video folder containing it).
    pred_dir : predicted masks, frame number in the name (``bin%06d.png`` or any ``*<digits>.png``).
    roi : ``ROI.bmp`` path or a mask array; ``None``: ``ROI.bmp`` of the video folder if present,
        else the whole image.
    temporal_roi : ``temporalROI.txt`` path or ``(first, last)``; ``None``: the video folder's file
        if present, else all ground-truth frames.
    frames : optional ``(first, last)`` further restricting the frames (intersected with the
        temporal ROI), e.g. to evaluate a subset.
    pred_prefix : only prediction files starting with this prefix.
    max_pixels : a mask or ROI file whose header claims more pixels is refused before decoding.

    Raises
    ------
    InputError
        Missing folders/files, a ground-truth frame without prediction, or size mismatches.
    """
    gt_dir = Path(gt_dir)
    if (gt_dir / "groundtruth").is_dir():
        gt_dir = gt_dir / "groundtruth"
    video = gt_dir.parent
    gt_files = find_frames(gt_dir)
    if not gt_files:
        raise InputError(f"{gt_dir}: no ground-truth masks found")
    pred_files = find_frames(pred_dir, pred_prefix)
    roi_arr = _spatial_roi(roi, video, max_pixels)
    lo, hi = _frame_range(gt_dir, gt_files, temporal_roi, frames)
    wanted = _complete_frames(gt_dir, pred_dir, gt_files, pred_files, lo, hi)
    log.debug("evaluating %d frames %d..%d", len(wanted), lo, hi)
    return evaluate_masks(_mask_pairs(wanted, gt_files, pred_files, roi_arr, max_pixels), roi_arr)


def _spatial_roi(roi: str | Path | np.ndarray | None, video: Path,
                 max_pixels: int = DEFAULT_MAX_PIXELS) -> np.ndarray | None:
    """The ROI as a bool mask: a file, an array, the video folder's ``ROI.bmp``, or None."""
    if roi is None and (video / "ROI.bmp").is_file():
        roi = video / "ROI.bmp"
    return read_roi(roi, max_pixels) if isinstance(roi, (str, Path)) else (
        None if roi is None else np.asarray(roi) != 0)


def _frame_range(gt_dir: Path, gt_files: dict[int, Path],
                 temporal_roi: str | Path | tuple[int, int] | None,
                 frames: tuple[int, int] | None) -> tuple[int, int]:
    """First and last frame to evaluate: the temporal ROI (the video folder's file by default,
    else all ground-truth frames) intersected with ``frames``."""
    video = gt_dir.parent
    if temporal_roi is None and (video / "temporalROI.txt").is_file():
        temporal_roi = video / "temporalROI.txt"
    if isinstance(temporal_roi, (str, Path)):
        temporal_roi = read_temporal_roi(temporal_roi)
    lo, hi = temporal_roi if temporal_roi is not None else (min(gt_files), max(gt_files))
    if frames is not None:
        lo, hi = max(lo, frames[0]), min(hi, frames[1])
    if lo > hi:
        raise InputError(f"{gt_dir}: no frames to evaluate (temporal ROI "
                         f"{temporal_roi if temporal_roi is not None else 'all'}, frames "
                         f"{frames if frames is not None else 'all'})")
    return lo, hi


def _complete_frames(gt_dir: Path, pred_dir: str | Path, gt_files: dict[int, Path],
                     pred_files: dict[int, Path], lo: int, hi: int) -> list[int]:
    """Frames ``lo..hi``, refused unless each has a ground truth and a prediction."""
    wanted = [f for f in range(lo, hi + 1) if f in gt_files]
    absent_gt = [f for f in range(lo, hi + 1) if f not in gt_files]
    if absent_gt:
        raise InputError(f"{gt_dir}: ground truth missing for {len(absent_gt)} frame(s) in "
                         f"{lo}..{hi}, e.g. {absent_gt[:5]}")
    missing = [f for f in wanted if f not in pred_files]
    if missing:
        raise InputError(f"{pred_dir}: no predicted mask for {len(missing)} frame(s) in "
                         f"{lo}..{hi}, e.g. {missing[:5]}")
    return wanted


def _mask_pairs(wanted: list[int], gt_files: dict[int, Path], pred_files: dict[int, Path],
                roi_arr: np.ndarray | None, max_pixels: int = DEFAULT_MAX_PIXELS
                ) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
    """``(frame, gt, pred)`` read one frame at a time, sizes checked against each other and the
    ROI."""
    for f in wanted:
        gt = read_mask(gt_files[f], max_pixels)
        pred = read_mask(pred_files[f], max_pixels)
        if gt.shape != pred.shape:
            raise InputError(f"{pred_files[f]}: size {pred.shape[::-1]} differs from the "
                             f"ground truth {gt.shape[::-1]} ({gt_files[f].name})")
        if roi_arr is not None and roi_arr.shape != gt.shape:
            raise InputError(f"ROI size {roi_arr.shape[::-1]} differs from the ground truth "
                             f"{gt.shape[::-1]} ({gt_files[f].name})")
        yield f, gt, pred
