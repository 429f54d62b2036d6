"""Point-distribution model (PDM) of pedestrian outlines.

An outline is a closed cubic B-spline with ``N`` control points (:mod:`.bspline`); stacking the
control points gives a shape vector ``x`` of length ``2N`` (``x0, y0, x1, y1, ...``). Following
Cootes, Taylor, Cooper & Graham, "Active Shape Models — their training and application", CVIU 61
(1995) and Baumberg & Hogg (1995) as used in the Reading People Tracker (Siebel 2003, section 2.3),
the model is learned (steps 1–2, :mod:`.training`) and applied (step 3, here):

1. **Alignment** (generalised Procrustes analysis, Cootes et al. 1995 section 3.2 / Gower 1975):
   every shape is centred, scaled to unit norm and rotated onto the current mean; the mean is
   re-estimated, normalised, and the loop repeats until it settles.
2. **PCA**: the covariance of the aligned shapes has eigenvectors ``P`` (modes) and eigenvalues
   ``lambda``; the ``t`` largest modes that explain a fraction ``xi`` of the total variance are kept
   (Cootes et al. eq. 5), so ``x ≈ mean + P b``.
3. **Constraint**: shape weights ``b`` are limited to the hyper-ellipsoid
   ``D_m^2 = sum_i b_i^2 / lambda_i <= D_max^2`` (Cootes et al. section 4.2, Siebel thesis
   section 2.3.3, ``D_max = 3``); a ``b`` outside is rescaled by ``D_max / D_m`` onto its surface.

Image placement uses a similarity transform ``(a, b, tx, ty)`` with ``X = a x - b y + tx``,
``Y = b x + a y + ty`` (scale ``s = sqrt(a^2 + b^2)``, angle ``atan2(b, a)``), linear in its
parameters so a weighted least-squares fit is a 4×4 solve (Cootes et al. appendix B).
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = [
    "ShapeModel",
    "fit_similarity",
    "weighted_similarity",
    "apply_similarity",
    "invert_similarity",
    "default_model_path",
    "load_default_model",
]

_FORMAT_VERSION = 1


# ------------------------------------------------------------------------------ pure geometry
def fit_similarity(src: np.ndarray, dst: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Weighted least-squares similarity transform mapping ``src`` onto ``dst``.

    Parameters
    ----------
    src, dst : (K, 2) float
        Corresponding points.
    weights : (K,) float >= 0, optional
        Per-point weights (default 1).

    Returns
    -------
    (4,) float64
        ``(a, b, tx, ty)`` minimising ``sum_k w_k |T(src_k) - dst_k|^2`` (Cootes et al. 1995,
        appendix B). With fewer than two weighted points the identity is returned.
    """
    s = np.asarray(src, dtype=np.float64).reshape(-1, 2)
    d = np.asarray(dst, dtype=np.float64).reshape(-1, 2)
    w = np.ones(len(s)) if weights is None else np.asarray(weights, dtype=np.float64).reshape(-1)
    return weighted_similarity(s, d, w)


def weighted_similarity(s: np.ndarray, d: np.ndarray, w: np.ndarray) -> np.ndarray:
    """:func:`fit_similarity` of float64 arrays ``(K, 2)``, ``(K, 2)``, ``(K,)`` as they are
    (no conversion: the shape tracker calls it twice per person and frame)."""
    if np.count_nonzero(w > 0) < 2:
        return np.array([1.0, 0.0, 0.0, 0.0])
    W = w.sum()
    if W <= 0:
        return np.array([1.0, 0.0, 0.0, 0.0])
    wc = w[:, None]
    msx, msy = ((wc * s).sum(axis=0) / W).tolist()
    mdx, mdy = ((wc * d).sum(axis=0) / W).tolist()
    s0, d0 = s - (msx, msy), d - (mdx, mdy)
    den = float((w * (s0 ** 2).sum(axis=1)).sum())
    if den <= 0:
        return np.array([1.0, 0.0, mdx - msx, mdy - msy])
    sx, sy, dx, dy = s0[:, 0], s0[:, 1], d0[:, 0], d0[:, 1]
    a = float((w * (sx * dx + sy * dy)).sum()) / den
    b = float((w * (sx * dy - sy * dx)).sum()) / den
    return np.array([a, b, mdx - (a * msx - b * msy), mdy - (b * msx + a * msy)])


def apply_similarity(pose: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Apply ``(a, b, tx, ty)`` to points ``(K, 2)``."""
    a, b, tx, ty = np.asarray(pose, dtype=np.float64).tolist()
    p = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
    x, y = p[:, 0], p[:, 1]
    out = np.empty((len(p), 2))
    out[:, 0] = a * x - b * y + tx
    out[:, 1] = b * x + a * y + ty
    return out


def invert_similarity(pose: np.ndarray) -> np.ndarray:
    """The inverse transform of ``(a, b, tx, ty)`` (requires ``a^2 + b^2 > 0``)."""
    a, b, tx, ty = np.asarray(pose, dtype=np.float64)
    s2 = a * a + b * b
    if s2 <= 0:
        raise ValueError("a similarity with zero scale has no inverse")
    ia, ib = a / s2, -b / s2
    return np.array([ia, ib, -(ia * tx - ib * ty), -(ib * tx + ia * ty)])


# ------------------------------------------------------------------------------------ the model
@dataclass(frozen=True, eq=False)
class ShapeModel:
    """A point-distribution model of closed B-spline outlines.

    Attributes
    ----------
    mean : (N, 2) float64
        Mean aligned control points (centred, unit norm, model frame).
    modes : (2N, t) float64
        Orthonormal modes of variation (columns), in ``x0, y0, x1, y1, ...`` order.
    variances : (t,) float64
        Eigenvalues ``lambda_i > 0`` (variance of each weight), descending.
    xi : float
        Fraction of the training variance the kept modes explain (requested).
    dmax : float
        Mahalanobis bound on the shape weights (Cootes et al.; Siebel thesis: 3).
    meta : dict
        Free-form provenance (training source, sample count, explained variance).
    """

    mean: np.ndarray
    modes: np.ndarray
    variances: np.ndarray
    xi: float = 0.95
    dmax: float = 3.0
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        mean = np.asarray(self.mean, dtype=np.float64)
        modes = np.asarray(self.modes, dtype=np.float64)
        var = np.asarray(self.variances, dtype=np.float64).reshape(-1)
        if mean.ndim != 2 or mean.shape[1] != 2 or mean.shape[0] < 4:
            raise ValueError(f"mean must have shape (N, 2) with N >= 4, got {mean.shape}")
        n2 = 2 * mean.shape[0]
        if modes.ndim != 2 or modes.shape[0] != n2 or modes.shape[1] != len(var):
            raise ValueError(f"modes must have shape ({n2}, {len(var)}), got {modes.shape}")
        if np.any(var <= 0) or not np.all(np.isfinite(var)):
            raise ValueError("shape-model variances must be finite and > 0")
        if not 0 < self.xi <= 1:
            raise ValueError(f"xi must be in (0, 1], got {self.xi}")
        if not self.dmax > 0:
            raise ValueError(f"dmax must be > 0, got {self.dmax}")
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "modes", modes)
        object.__setattr__(self, "variances", var)
        for a in (mean, modes, var):
            a.setflags(write=False)

    @property
    def n_control(self) -> int:
        return int(self.mean.shape[0])

    @property
    def n_modes(self) -> int:
        return int(len(self.variances))

    def shape(self, b: np.ndarray | None = None) -> np.ndarray:
        """Control points ``(N, 2)`` in the model frame for weights ``b`` ``(t,)`` (None = mean)."""
        if b is None or self.n_modes == 0:
            return self.mean.copy()
        x = self.mean.reshape(-1) + self.modes @ np.asarray(b, dtype=np.float64).reshape(-1)
        return x.reshape(-1, 2)

    def project(self, control: np.ndarray) -> np.ndarray:
        """Weights ``b = P^T (x - mean)`` ``(t,)`` of control points already in the model frame."""
        x = np.asarray(control, dtype=np.float64).reshape(-1) - self.mean.reshape(-1)
        return self.modes.T @ x

    def mahalanobis(self, b: np.ndarray) -> float:
        """``D_m = sqrt(sum_i b_i^2 / lambda_i)`` (Cootes et al. 1995, eq. 13)."""
        b = np.asarray(b, dtype=np.float64).reshape(-1)
        return float(np.sqrt(np.sum(b * b / self.variances))) if len(b) else 0.0

    def constrain(self, b: np.ndarray) -> np.ndarray:
        """``b`` itself when ``D_m <= dmax``; otherwise ``b * dmax / D_m`` (onto the hyper-ellipsoid)."""
        b = np.asarray(b, dtype=np.float64).reshape(-1)
        d = self.mahalanobis(b)
        return b.copy() if d <= self.dmax else b * (self.dmax / d)

    def fit(self, control: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Best model instance for image control points ``(N, 2)``.

        Returns ``(pose, b)``: the similarity placing the model in the image and the constrained
        weights, from two rounds of pose fit → inverse-map → project → constrain.
        """
        c = np.asarray(control, dtype=np.float64)
        b = np.zeros(self.n_modes)
        pose = fit_similarity(self.shape(b), c)
        for _ in range(2):
            local = apply_similarity(invert_similarity(pose), c)
            b = self.constrain(self.project(local))
            pose = fit_similarity(self.shape(b), c)
        return pose, b

    # ------------------------------------------------------------------ persistence
    def to_bytes(self) -> bytes:
        """The model as a compressed ``.npz`` file's bytes, the format :meth:`load` reads
        (:func:`~.training.save_model` writes them to a file)."""
        buf = io.BytesIO()
        np.savez_compressed(
            buf, version=np.int64(_FORMAT_VERSION), mean=self.mean.astype(np.float32),
            modes=self.modes.astype(np.float32), variances=self.variances,
            xi=np.float64(self.xi), dmax=np.float64(self.dmax),
            meta=np.array(json.dumps(self.meta, sort_keys=True)))
        return buf.getvalue()

    @classmethod
    def load(cls, path: str | Path) -> "ShapeModel":
        """Read a model file (:meth:`to_bytes`); a bad file raises :class:`InputError`."""
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as z:
                version = int(z["version"])
                if version != _FORMAT_VERSION:
                    raise InputError(f"{path}: shape model format version {version}, expected "
                                     f"{_FORMAT_VERSION}")
                return cls(mean=z["mean"].astype(np.float64), modes=z["modes"].astype(np.float64),
                           variances=z["variances"], xi=float(z["xi"]), dmax=float(z["dmax"]),
                           meta=json.loads(str(z["meta"])))
        except InputError:
            raise
        except (OSError, KeyError, ValueError, EOFError, TypeError) as e:
            raise InputError(f"{path}: not a shape model ({e})") from None


def default_model_path() -> Path:
    """Path of the shipped default model (trained on the synthetic figures)."""
    return Path(__file__).resolve().parents[1] / "data" / "shape_model_default.npz"


def load_default_model() -> ShapeModel:
    """The shipped default :class:`ShapeModel` (see ``tools/train_shape_model.py``)."""
    return ShapeModel.load(default_model_path())
