"""Ground plane from point pairs: a homography for users with no calibration target.

Given ``N >= 4`` image points and their positions on the ground (metres), the plane-to-plane map is
a homography ``x_world ~ H x_image`` (Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., §4.1,
normalised DLT, alg. 4.2). We estimate it with ``cv2.findHomography`` (least squares over all pairs,
Hartley normalisation inside OpenCV). When the camera intrinsics are known (a chessboard YAML), the
same pairs instead give a full pose with ``cv2.solvePnP``, so heights can be measured too.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import tomli_w


from ..errors import ConfigError, InputError, excerpt, location
from ..io.atomic import atomic_write_text
from ..io.textfile import read_text
from ..io.tomlfile import read_toml
from .chessboard import OpenCVCamera
from .tsai import MAX_IMAGE_SIDE, _as_pixels, _as_world, _kind, pixel_scaling

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

    def resized(self, width: int, height: int) -> "GroundHomography":
        """The same map for its video scaled to ``width`` x ``height`` pixels (needs
        :attr:`size`): new pixels go back to the calibration's
        (:func:`~motiontrack.calibrate.tsai.pixel_scaling`) before ``H``."""
        if self.size is None:
            raise ConfigError("a ground homography without its image size cannot be resized")
        A = pixel_scaling(self.size, (width, height))
        return GroundHomography(H=self.H @ np.linalg.inv(A), size=(int(width), int(height)),
                                rms=self.rms)


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
    _check_spread(img, "image")
    _check_spread(wld, "world")
    H, _ = cv2.findHomography(np.ascontiguousarray(img), np.ascontiguousarray(wld), 0)
    if H is None:
        raise InputError("point pairs are degenerate (three or more collinear?): no homography")
    try:
        g = GroundHomography(H=H, size=size)
    except ValueError:
        raise InputError("point pairs are degenerate: the fitted homography is singular (are "
                         "the points nearly on one line?)") from None
    res = np.linalg.norm(g.image_to_world(img) - wld, axis=1)
    return GroundHomography(H=H, size=size, rms=float(np.sqrt(np.mean(res ** 2))))


def _check_spread(pts: np.ndarray, what: str) -> None:
    """:class:`InputError` when the points do not span a plane: all on one line (or one point),
    from which no homography follows."""
    centred = pts - pts.mean(axis=0)
    s = np.linalg.svd(centred, compute_uv=False)
    if not (s[0] > 0 and s[1] > 1e-9 * s[0]):
        raise InputError(f"the {len(pts)} {what} points lie on one line (or are one point): a "
                         "ground homography needs points spread over the plane, at least 4 with "
                         "no 3 on a line")


def fit_pose(camera, image_pts: np.ndarray, world_pts: np.ndarray):
    """Ground pose for an :class:`OpenCVCamera` with intrinsics from ``N >= 4`` pairs (solvePnP)."""
    img = _as_pixels(image_pts)
    wld = _as_world(world_pts)
    if len(img) < 4 or len(img) != len(wld):
        raise InputError(f"pose needs at least 4 matching point pairs, got {len(img)}/{len(wld)}")
    _check_spread(img, "image")
    _check_spread(wld[:, :2], "world")
    try:
        ok, rvec, tvec = cv2.solvePnP(np.ascontiguousarray(wld), np.ascontiguousarray(img),
                                      camera.K, camera.dist, flags=cv2.SOLVEPNP_ITERATIVE)
    except cv2.error:
        ok = False
    if not ok or not (np.isfinite(rvec).all() and np.isfinite(tvec).all()):
        raise InputError("solvePnP failed for these point pairs")
    return OpenCVCamera(K=camera.K, dist=camera.dist, size=camera.size, rvec=rvec.reshape(3),
                        tvec=tvec.reshape(3))


def read_point_pairs(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """CSV with columns ``u,v,x,y`` (pixels, metres) and an optional header; ``#`` comments.

    Returns ``(image (N, 2), world (N, 2))`` float64.
    """
    p = Path(path)
    rows = []
    for lineno, fields in read_csv_fields(p, "point-pairs file"):
        if not fields or not fields[0][1] or fields[0][1].startswith("#"):
            continue
        if lineno == 1 and not rows and not _is_number(fields[0][1]):
            continue  # header
        if len(fields) not in (4, 5):
            raise InputError(f"{location(p, lineno)}: expected 4 finite values u,v,x,y, found "
                             f"{len(fields)}")
        vals = []
        for col, text in fields:
            if not _is_number(text):
                raise InputError(f"{location(p, lineno, col)}: expected numbers u,v,x,y, got "
                                 f"{excerpt(text)}")
            v = float(text)
            if not math.isfinite(v):
                raise InputError(f"{location(p, lineno, col)}: expected 4 finite values u,v,x,y, "
                                 f"got {excerpt(text)}")
            vals.append(v)
        rows.append(vals[:4])
    a = np.asarray(rows, dtype=np.float64).reshape(-1, 4)
    return a[:, :2], a[:, 2:4]


#: largest CSV of points or lines read (they hold tens to thousands of rows)
MAX_CSV_BYTES = 64 * 2**20


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_csv_fields(path: Path, what: str) -> list[tuple[int, list[tuple[int, str]]]]:
    """The rows of a small comma-separated text file: ``(line number, [(column, field), ...])``
    with 1-based line numbers and character columns, fields stripped of surrounding blanks.

    A missing file, a folder, a file larger than :data:`MAX_CSV_BYTES` or one that is not UTF-8
    text is an :class:`InputError` naming ``what``. No quoting: these files hold numbers and
    names.
    """
    text = read_text(path, what, MAX_CSV_BYTES)
    out = []
    for lineno, line in enumerate(text.splitlines(), 1):
        fields, start = [], 0
        for part in line.split(","):
            lead = len(part) - len(part.lstrip())
            fields.append((start + lead + 1, part.strip()))
            start += len(part) + 1
        out.append((lineno, fields if line.strip() else []))
    return out


def write_ground_toml(g: GroundHomography, path: str | Path) -> None:
    doc = {"model": "homography", "units": {"world": "m", "image": "px"},
           "H": [[float(v) for v in row] for row in g.H]}
    if g.size is not None:
        doc["width"], doc["height"] = int(g.size[0]), int(g.size[1])
    if np.isfinite(g.rms):
        doc["rms_m"] = float(g.rms)
    atomic_write_text(path, tomli_w.dumps(doc))


def ground_from_toml_doc(doc: dict, name: str) -> GroundHomography:
    """A :class:`GroundHomography` from our TOML layout (see :func:`write_ground_toml`): ``H`` a
    3x3 array of finite numbers, optional whole ``width`` and ``height`` in pixels, optional
    ``rms_m``; a bad value is an :class:`InputError` naming it (never quoting the file)."""
    where = f"{location(name)}: invalid homography camera"
    H = doc.get("H")
    if H is None:
        raise InputError(f"{where}: no H (3x3 array, image pixels to ground metres)")
    if not (isinstance(H, list) and len(H) == 3
            and all(isinstance(r, list) and len(r) == 3 for r in H)):
        raise InputError(f"{where}: H must be a 3x3 array of numbers")
    flat = [_toml_number(v, f"{where}: H", name) for r in H for v in r]
    size = None
    if "width" in doc or "height" in doc:
        size = tuple(_toml_side(doc.get(k), f"{where}: {k}") for k in ("width", "height"))
    rms = _toml_number(doc.get("rms_m", math.nan), f"{where}: rms_m", name, nan_ok=True)
    try:
        return GroundHomography(H=np.asarray(flat, dtype=np.float64).reshape(3, 3), size=size,
                                rms=rms)
    except ValueError:
        raise InputError(f"{where}: H must be invertible") from None


def _toml_number(v: object, where: str, name: str, nan_ok: bool = False) -> float:
    """A TOML number as a finite float (or NaN, "unknown", with ``nan_ok``)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)) or (
            isinstance(v, int) and not abs(v) < 1e300):
        raise InputError(f"{where} must be numbers, got {_kind(v)}")
    if not (math.isfinite(v) or (nan_ok and math.isnan(v))):
        raise InputError(f"{where} must be finite numbers, got {v}")
    return float(v)


def _toml_side(v: object, where: str) -> int:
    """An image width or height from a camera file: a whole number of pixels."""
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not (
            float(v).is_integer() and 1 <= v <= MAX_IMAGE_SIDE):
        raise InputError(f"{where} must be a whole number of pixels in [1, {MAX_IMAGE_SIDE}], "
                         f"got {v if isinstance(v, (int, float)) else _kind(v)}")
    return int(v)


def read_ground_toml(path: str | Path) -> GroundHomography:
    return ground_from_toml_doc(read_toml(path, "camera TOML"), str(path))
