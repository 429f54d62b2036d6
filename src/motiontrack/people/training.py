"""Training the point-distribution model of pedestrian outlines (:mod:`.shape_model`).

Following Cootes, Taylor, Cooper & Graham, "Active Shape Models — their training and application",
CVIU 61 (1995), as used in the Reading People Tracker (Siebel 2003, section 2.3):

1. **Outlines**: the largest blob of a person's mask is traced from its topmost pixel with positive
   signed area and fitted with a closed cubic B-spline (:mod:`.bspline`), so the control points of
   different people correspond. Masks come from a synthetic scene's exact masks
   (:func:`outlines_from_synth`) or from motion masks inside ground-truth boxes
   (:func:`outlines_from_video`); only isolated, fully visible people are used.
2. **Alignment** (generalised Procrustes analysis, Cootes et al. 1995 section 3.2 / Gower 1975):
   every shape is centred, scaled to unit norm and rotated onto the current mean; the mean is
   re-estimated, normalised, and the loop repeats until it settles.
3. **PCA**: the covariance of the aligned shapes has eigenvectors ``P`` (modes) and eigenvalues
   ``lambda``; the ``t`` largest modes that explain a fraction ``xi`` of the total variance are kept
   (Cootes et al. eq. 5), so ``x ≈ mean + P b`` (:func:`train_shape_model`).

:func:`train_from_synth` with :data:`DEFAULT_TRAINING` is the recipe of the shipped default model
(``tools/train_shape_model.py``); :func:`save_model` writes a model for :meth:`ShapeModel.load`.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Iterable, Iterator

import cv2
import numpy as np

from ..config import CleanupConfig, MotionConfig
from ..io.atomic import atomic_write_bytes
from ..io.sources import open_source
from ..motion import clean_mask, create_detector
from ..synth import MASK_PERSON, make_scene
from ..types import frame_number
from . import bspline
from .shape_model import ShapeModel, apply_similarity, fit_similarity

log = logging.getLogger(__name__)

__all__ = [
    "normalize_shape",
    "align_to",
    "generalized_procrustes",
    "train_shape_model",
    "outline_from_mask",
    "control_points_from_mask",
    "outlines_from_synth",
    "outlines_from_video",
    "DEFAULT_TRAINING",
    "train_from_synth",
    "save_model",
]


# -------------------------------------------------------------------------- alignment and PCA
def normalize_shape(c: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Centre a shape ``(N, 2)`` on its centroid and scale it to unit Frobenius norm.

    Returns
    -------
    shape : (N, 2) float64
    centroid : (2,) float64
    norm : float
        The norm the centred shape had (its size); 0-size shapes are returned centred, unscaled.
    """
    c = np.asarray(c, dtype=np.float64)
    centroid = c.mean(axis=0) if len(c) else np.zeros(2)
    centred = c - centroid
    norm = float(np.linalg.norm(centred))
    return (centred / norm if norm > 0 else centred), centroid, norm


def align_to(shape: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Rotate a centred unit-norm shape ``(N, 2)`` onto ``ref`` (orthogonal Procrustes, no scaling)."""
    pose = fit_similarity(shape, ref)
    s = np.hypot(pose[0], pose[1])
    if s <= 0:
        return np.asarray(shape, dtype=np.float64).copy()
    rot = np.array([pose[0] / s, pose[1] / s, 0.0, 0.0])
    return apply_similarity(rot, shape)


def generalized_procrustes(shapes: np.ndarray, iterations: int = 20, tol: float = 1e-10
                           ) -> tuple[np.ndarray, np.ndarray]:
    """Generalised Procrustes alignment of ``S`` shapes ``(S, N, 2)`` (Cootes et al. 1995, sec. 3.2).

    Returns
    -------
    aligned : (S, N, 2) float64
        Each shape centred, unit norm, rotated onto the mean.
    mean : (N, 2) float64
        Unit-norm mean, its rotation fixed by the first shape (the gauge of the alignment).
    """
    x = np.asarray(shapes, dtype=np.float64)
    if x.ndim != 3 or x.shape[2] != 2:
        raise ValueError(f"shapes must have shape (S, N, 2), got {x.shape}")
    if len(x) == 0:
        return x.copy(), np.zeros(x.shape[1:])
    norm = np.stack([normalize_shape(s)[0] for s in x])
    mean = norm[0].copy()
    aligned = norm
    for _ in range(max(1, iterations)):
        aligned = np.stack([align_to(s, mean) for s in norm])
        new = normalize_shape(aligned.mean(axis=0))[0]
        new = align_to(new, norm[0])  # fix the gauge: the mean's orientation follows shape 0
        done = float(np.linalg.norm(new - mean)) < tol
        mean = new
        if done:
            break
    aligned = np.stack([align_to(s, mean) for s in norm])
    return aligned, mean


def train_shape_model(shapes: Iterable[np.ndarray], xi: float = 0.95, dmax: float = 3.0,
                      max_modes: int = 20, meta: dict | None = None) -> ShapeModel:
    """Learn a :class:`ShapeModel` from control-point sets.

    Parameters
    ----------
    shapes : iterable of (N, 2) float
        Control points of training outlines (any position/scale/rotation; same N, corresponding
        start points, e.g. from :func:`control_points_from_mask`).
    xi : float in (0, 1]
        Keep the fewest modes whose eigenvalues sum to at least ``xi`` of the total variance.
    dmax : float
        Mahalanobis bound stored with the model.
    max_modes : int
        Upper limit on kept modes.

    Raises
    ------
    ValueError
        Fewer than 2 shapes, or shapes without variation.
    """
    arr = np.asarray([np.asarray(s, dtype=np.float64) for s in shapes])
    if arr.ndim != 3 or len(arr) < 2:
        raise ValueError(f"need at least 2 training shapes of shape (N, 2), got {arr.shape}")
    aligned, mean = generalized_procrustes(arr)
    X = aligned.reshape(len(arr), -1)
    C = np.cov(X - mean.reshape(-1), rowvar=False, bias=True)
    lam, vec = np.linalg.eigh(C)
    order = np.argsort(lam)[::-1]
    lam, vec = np.clip(lam[order], 0.0, None), vec[:, order]
    total = float(lam.sum())
    if total <= 0:
        raise ValueError("training shapes do not vary: cannot learn modes")
    frac = np.cumsum(lam) / total
    t = int(np.searchsorted(frac, xi - 1e-12) + 1)
    t = max(1, min(t, max_modes, int(np.count_nonzero(lam > total * 1e-12))))
    info = dict(meta or {})
    info.update({"samples": int(len(arr)), "explained": float(frac[t - 1]), "modes": t})
    return ShapeModel(mean=mean, modes=vec[:, :t], variances=lam[:t], xi=xi, dmax=dmax, meta=info)


# ------------------------------------------------------------------- outlines from masks
def outline_from_mask(mask: np.ndarray) -> np.ndarray | None:
    """The largest external contour of a binary mask as an ordered outline ``(M, 2)``.

    The outline starts at its topmost pixel (the top of the head for a standing person; ties go to
    the one nearest the middle of the tied run) and runs with positive :func:`bspline.signed_area`,
    so outlines of different people correspond point-for-point by arc length.
    Returns ``None`` when the mask is empty.
    """
    m = (np.asarray(mask) > 0).astype(np.uint8)
    if not m.any():
        return None
    m = cv2.copyMakeBorder(m, 1, 1, 1, 1, cv2.BORDER_CONSTANT, value=0)
    contours, _ = cv2.findContours(m, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return None
    c = max(contours, key=cv2.contourArea).reshape(-1, 2).astype(np.float64) - 1.0
    if bspline.signed_area(c) < 0:
        c = c[::-1]
    top = np.flatnonzero(c[:, 1] == c[:, 1].min())
    xs = c[top, 0]
    start = int(top[np.argmin(np.abs(xs - np.median(xs)))])
    return np.roll(c, -start, axis=0)


def control_points_from_mask(mask: np.ndarray, n_control: int = 32, min_points: int = 40
                             ) -> np.ndarray | None:
    """Least-squares spline control points ``(n_control, 2)`` of the largest blob in ``mask``.

    ``None`` when the outline has fewer than ``max(min_points, n_control)`` pixels.
    """
    c = outline_from_mask(mask)
    if c is None or len(c) < max(min_points, n_control):
        return None
    return bspline.fit_closed(c, n_control)


def _isolated(boxes: np.ndarray, margin: float) -> np.ndarray:
    """Boolean ``(K,)``: box k does not touch any other box grown by ``margin`` px."""
    k = len(boxes)
    ok = np.ones(k, dtype=bool)
    for i in range(k):
        for j in range(k):
            if i == j:
                continue
            a, b = boxes[i], boxes[j]
            if (a[0] < b[0] + b[2] + margin and b[0] - margin < a[0] + a[2]
                    and a[1] < b[1] + b[3] + margin and b[1] - margin < a[1] + a[3]):
                ok[i] = False
                break
    return ok


def _crop_shape(mask: np.ndarray, box: np.ndarray, n_control: int, min_height: float,
                min_fill: float) -> np.ndarray | None:
    """Control points of the person inside ``box`` of a 0/255 mask, or None when unusable."""
    H, W = mask.shape[:2]
    x, y, w, h = box
    if h < min_height or x < 0 or y < 0 or x + w > W or y + h > H:
        return None  # too small or cut by the image border
    x1, y1 = int(np.floor(x)), int(np.floor(y))
    x2, y2 = int(np.ceil(x + w)), int(np.ceil(y + h))
    crop = mask[y1:y2, x1:x2] > 127
    if crop.size == 0 or crop.mean() < min_fill:
        return None
    n, lab, stats, _ = cv2.connectedComponentsWithStats(crop.astype(np.uint8), connectivity=8)
    if n < 2:
        return None
    big = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    if stats[big, cv2.CC_STAT_HEIGHT] < 0.8 * (y2 - y1):
        return None  # the blob does not span the person (fragmented mask)
    c = control_points_from_mask(lab == big, n_control)
    return None if c is None else c + np.array([x1, y1], dtype=np.float64)


def outlines_from_synth(name: str = "walker", seeds: Iterable[int] = (0,), n_control: int = 32,
                        every: int = 3, min_height: float = 40.0) -> Iterator[np.ndarray]:
    """Control points of isolated, fully visible people in a synthetic scene's exact masks.

    Yields ``(n_control, 2)`` arrays in image pixels, one per usable person and frame (every
    ``every``-th frame; people touching the border or another person are skipped).
    """
    for seed in seeds:
        scene = make_scene(name, seed=int(seed))
        gt = scene.ground_truth()
        rows = gt.by_frame()
        for frame_no in sorted(rows):
            if (frame_no - 1) % max(1, every):
                continue
            g = gt.select(np.isin(np.arange(len(gt)), rows[frame_no]))
            boxes = g.boxes
            iso = _isolated(boxes, margin=4.0) & (g.visibility >= 0.999)
            if not iso.any():
                continue
            mask = np.where(scene.foreground_mask(frame_no - 1) == MASK_PERSON, 255, 0).astype(np.uint8)
            for k in np.flatnonzero(iso):
                c = _crop_shape(mask, boxes[k], n_control, min_height, min_fill=0.2)
                if c is not None:
                    yield c


def outlines_from_video(source, gt, n_control: int = 32, every: int = 2, min_height: float = 40.0,
                        warmup: int = 20, max_frames: int = 0) -> Iterator[np.ndarray]:
    """Control points of isolated people from motion masks inside ground-truth boxes.

    Parameters
    ----------
    source : str or iterable of Frame
        Anything :func:`motiontrack.io.sources.open_source` accepts.
    gt : Annotations
        Ground truth (1-based frames = video frame index + 1).
    n_control, every, min_height
        Spline size; use every ``every``-th frame; skip people shorter than ``min_height`` px.
    warmup : int
        Frames fed to the background model before masks are used.
    max_frames : int
        Stop after this many frames (0 = all).

    The motion mask comes from MOG2 (shadows removed) at full resolution, cleaned with the default
    clean-up; a person is used when their gt box does not touch another box, lies inside the image
    and the largest blob inside it spans at least 80 % of its height.
    """
    det = create_detector(MotionConfig(method="mog2"))
    rows = gt.by_frame()
    src = open_source(source) if isinstance(source, str) else source
    for k, frame in enumerate(src):
        if max_frames and k >= max_frames:
            break
        mask = clean_mask(det.apply(frame.image), CleanupConfig())
        fno = frame_number(frame.index)
        if frame.index < warmup or fno not in rows or (frame.index % max(1, every)):
            continue
        g = gt.select(np.isin(np.arange(len(gt)), rows[fno]))
        iso = _isolated(g.boxes, margin=4.0) & g.consider
        for j in np.flatnonzero(iso):
            c = _crop_shape(mask, g.boxes[j], n_control, min_height, min_fill=0.25)
            if c is not None:
                yield c


# --------------------------------------------------------------- the shipped default model
#: Training set of the shipped default model: (scene, seeds) pairs of synthetic figures.
DEFAULT_TRAINING = (("walker", tuple(range(6))), ("runner", tuple(range(3))), ("crossing", (0, 1)))


def train_from_synth(scenes=DEFAULT_TRAINING, n_control: int = 32, xi: float = 0.95,
                     dmax: float = 3.0, every: int = 3) -> ShapeModel:
    """Train a model on exact masks of synthetic figures (the shipped default's recipe).

    Parameters
    ----------
    scenes : sequence of (name, seeds)
        Synthetic scene types and seeds to render.
    n_control, xi, dmax, every
        Spline size, variance fraction, Mahalanobis bound, frame step.

    Raises
    ------
    ValueError
        Fewer than 2 usable outlines.
    """
    shapes = []
    for name, seeds in scenes:
        shapes.extend(outlines_from_synth(name, seeds=seeds, n_control=n_control, every=every))
    log.info("training shape model on %d synthetic outlines", len(shapes))
    meta = {"source": "synth:" + ",".join(f"{n}{list(s)}" for n, s in scenes), "every": every,
            "n_control": n_control}
    return train_shape_model(shapes, xi=xi, dmax=dmax, meta=meta)


def save_model(model: ShapeModel, path: str | Path) -> Path:
    """Write ``model`` as a compressed ``.npz`` (atomically), the file :meth:`ShapeModel.load` reads."""
    path = Path(path)
    atomic_write_bytes(path, model.to_bytes())
    return path
