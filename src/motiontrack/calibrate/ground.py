"""Ground plane from point pairs: a homography for users with no calibration target.

Given ``N >= 4`` image points and their positions on the ground (metres), the plane-to-plane map is
a homography ``x_world ~ H x_image`` (Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., §4.1,
normalised DLT, alg. 4.2). We estimate it with ``cv2.findHomography`` (least squares over all pairs,
Hartley normalisation inside OpenCV). When the camera intrinsics are known (a chessboard YAML), the
same pairs instead give a full pose with ``cv2.solvePnP``, so heights can be measured too.
"""

from __future__ import annotations

import csv
import io
import logging
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import tomli_w


from ..errors import ConfigError, InputError
from ..io.atomic import atomic_write_text
from ..io.tomlfile import read_toml
from .chessboard import OpenCVCamera
from .tsai import _as_pixels, _as_world

log = logging.getLogger(__name__)

__all__ = ["GroundHomography", "fit_homography", "fit_pose", "read_point_pairs",
           "read_ground_toml", "write_ground_toml", "ground_from_toml_doc"]


@dataclass(frozen=True, eq=False)
class GroundHomography:
    """Image ↔ ground-plane map ``[X, Y, 1]ᵀ ~ H [u, v, 1]ᵀ`` (pixels → metres).

    Attributes
    ----------
    H : (3, 3) float64
        Image → world homography, normalised so ``H[2, 2] = 1``.
    size : (int, int) or None
        Image width, height (pixels), informative.
    rms : float
        RMS ground-plane residual of the fitted pairs (metres); NaN when unknown.
    """

    H: np.ndarray
    size: tuple[int, int] | None = None
    rms: float = float("nan")

    def __post_init__(self) -> None:
        H = np.asarray(self.H, dtype=np.float64)
        if H.shape != (3, 3) or not np.all(np.isfinite(H)) or abs(np.linalg.det(H)) < 1e-300:
            raise ValueError(f"homography must be a finite, invertible 3x3 matrix, got {H.tolist()}")
        object.__setattr__(self, "H", H / H[2, 2] if H[2, 2] != 0 else H)

    @property
    def image_size(self) -> tuple[int, int] | None:
        return self.size

    def image_to_world(self, pixels: np.ndarray) -> np.ndarray:
        """(N, 2) pixels → (N, 2) ground ``X, Y`` metres (NaN on the horizon line)."""
        return _apply(self.H, _as_pixels(pixels))

    def world_to_image(self, points: np.ndarray, distorted: bool = True) -> np.ndarray:
        """(N, 2) or (N, 3) world metres with ``Z = 0`` → (N, 2) pixels."""
        P = _as_world(points)
        if len(P) and np.any(P[:, 2] != 0):
            raise ConfigError("a ground-plane homography can only project points with Z = 0")
        return _apply(np.linalg.inv(self.H), P[:, :2])

    def undistort(self, image: np.ndarray) -> np.ndarray:
        """No lens model: the image is returned unchanged (a copy)."""
        return image.copy()


def _apply(H: np.ndarray, pts: np.ndarray) -> np.ndarray:
    if len(pts) == 0:
        return np.zeros((0, 2))
    q = np.hstack([pts, np.ones((len(pts), 1))]) @ H.T
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(np.abs(q[:, 2]) > 1e-12, q[:, 2], np.nan)
        return q[:, :2] / w[:, None]


def fit_homography(image_pts: np.ndarray, world_pts: np.ndarray,
                   size: tuple[int, int] | None = None) -> GroundHomography:
    """Least-squares homography from ``N >= 4`` pairs (pixels (N, 2) → metres (N, 2))."""
    img = _as_pixels(image_pts)
    wld = np.asarray(world_pts, dtype=np.float64)
    wld = wld.reshape(-1, wld.shape[-1])[:, :2] if wld.size else np.zeros((0, 2))
    if len(img) != len(wld):
        raise ConfigError(f"need as many image as world points, got {len(img)} and {len(wld)}")
    if len(img) < 4:
        raise InputError(f"a ground homography needs at least 4 point pairs, got {len(img)}")
    H, _ = cv2.findHomography(np.ascontiguousarray(img), np.ascontiguousarray(wld), 0)
    if H is None:
        raise InputError("point pairs are degenerate (three or more collinear?): no homography")
    g = GroundHomography(H=H, size=size)
    res = np.linalg.norm(g.image_to_world(img) - wld, axis=1)
    return GroundHomography(H=H, size=size, rms=float(np.sqrt(np.mean(res ** 2))))


def fit_pose(camera, image_pts: np.ndarray, world_pts: np.ndarray):
    """Ground pose for an :class:`OpenCVCamera` with intrinsics from ``N >= 4`` pairs (solvePnP)."""
    img = _as_pixels(image_pts)
    wld = _as_world(world_pts)
    if len(img) < 4 or len(img) != len(wld):
        raise InputError(f"pose needs at least 4 matching point pairs, got {len(img)}/{len(wld)}")
    ok, rvec, tvec = cv2.solvePnP(np.ascontiguousarray(wld), np.ascontiguousarray(img), camera.K,
                                  camera.dist, flags=cv2.SOLVEPNP_ITERATIVE)
    if not ok:
        raise InputError("solvePnP failed for these point pairs")
    return OpenCVCamera(K=camera.K, dist=camera.dist, size=camera.size, rvec=rvec.reshape(3),
                        tvec=tvec.reshape(3))


def read_point_pairs(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """CSV with columns ``u,v,x,y`` (pixels, metres) and an optional header; ``#`` comments.

    Returns ``(image (N, 2), world (N, 2))`` float64.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"point-pairs file not found: {p}")
    rows = []
    for lineno, rec in enumerate(csv.reader(io.StringIO(p.read_text(encoding="utf-8-sig"))), 1):
        rec = [c.strip() for c in rec]
        if not rec or not rec[0] or rec[0].startswith("#"):
            continue
        try:
            vals = [float(c) for c in rec]
        except ValueError:
            if not rows and lineno == 1:
                continue  # header
            raise InputError(f"{p}:{lineno}: expected numbers u,v,x,y, got {','.join(rec)!r}") from None
        if len(vals) not in (4, 5) or not np.all(np.isfinite(vals)):
            raise InputError(f"{p}:{lineno}: expected 4 finite values u,v,x,y, got {','.join(rec)!r}")
        rows.append(vals[:4])
    a = np.asarray(rows, dtype=np.float64).reshape(-1, 4)
    return a[:, :2], a[:, 2:4]


def write_ground_toml(g: GroundHomography, path: str | Path) -> None:
    doc = {"model": "homography", "units": {"world": "m", "image": "px"},
           "H": [[float(v) for v in row] for row in g.H]}
    if g.size is not None:
        doc["width"], doc["height"] = int(g.size[0]), int(g.size[1])
    if np.isfinite(g.rms):
        doc["rms_m"] = float(g.rms)
    atomic_write_text(path, tomli_w.dumps(doc))


def ground_from_toml_doc(doc: dict, name: str) -> GroundHomography:
    try:
        H = np.asarray(doc["H"], dtype=np.float64)
        size = (int(doc["width"]), int(doc["height"])) if "width" in doc else None
        return GroundHomography(H=H, size=size, rms=float(doc.get("rms_m", float("nan"))))
    except (KeyError, ValueError, TypeError) as exc:
        raise InputError(f"{name}: invalid homography camera: {exc}") from None


def read_ground_toml(path: str | Path) -> GroundHomography:
    return ground_from_toml_doc(read_toml(path, "camera TOML"), str(path))
