"""OpenCV (Zhang 2000) calibration from chessboard photos, and the OpenCV pinhole camera.

Steps (Zhang, "A flexible new technique for camera calibration", PAMI 2000; OpenCV
``calib3d`` tutorial): find the inner corners of a ``cols × rows`` chessboard in each photo, refine
them to sub-pixel accuracy (``cv2.cornerSubPix``), then ``cv2.calibrateCamera`` estimates the camera
matrix ``K``, the distortion ``(k1, k2, p1, p2, k3)`` (Brown–Conrady) and one pose per view by
minimising the reprojection error with Levenberg–Marquardt.

The YAML written by :func:`write_opencv_yaml` is the layout of OpenCV's own ``calibration.cpp``
sample (``camera_matrix``, ``distortion_coefficients``, ``avg_reprojection_error``,
``per_view_reprojection_errors``, ``extrinsic_parameters``) so ``cv2.FileStorage`` reads it.
"""

from __future__ import annotations

import functools
import logging
import math
import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import cv2
import numpy as np

from ..errors import ConfigError, InputError, location, printable
from ..io.atomic import commit_temp, temp_path_for
from ..io.textfile import read_text
from ..imaging import to_gray
from .tsai import MAX_IMAGE_SIDE, _as_pixels, _as_world, _intersect_plane, pixel_scaling

log = logging.getLogger(__name__)

__all__ = [
    "OpenCVCamera",
    "ChessboardResult",
    "board_points",
    "find_corners",
    "calibrate_chessboard",
    "write_opencv_yaml",
    "read_opencv_yaml",
    "parse_pattern",
]


@dataclass(frozen=True, eq=False)
class OpenCVCamera:
    """Pinhole camera with OpenCV distortion and, optionally, a pose of the ground plane.

    Attributes
    ----------
    K : (3, 3) float64
        Camera matrix (pixels).
    dist : (k,) float64
        Distortion coefficients ``(k1, k2, p1, p2[, k3, ...])``.
    size : (int, int)
        Image width, height (pixels).
    rvec, tvec : (3,) float64 or None
        World → camera pose (Rodrigues vector, translation in metres) of the ground plane ``Z = 0``;
        without it the camera can undistort but not measure.
    """

    K: np.ndarray
    dist: np.ndarray
    size: tuple[int, int]
    rvec: np.ndarray | None = None
    tvec: np.ndarray | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        K = np.asarray(self.K, dtype=np.float64)
        if K.shape != (3, 3) or not np.all(np.isfinite(K)) or K[0, 0] <= 0 or K[1, 1] <= 0:
            raise ValueError(f"camera matrix must be a finite 3x3 with fx, fy > 0, got {K.tolist()}")
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "dist", np.asarray(self.dist, dtype=np.float64).reshape(-1))
        for n in ("rvec", "tvec"):
            v = getattr(self, n)
            if v is not None:
                object.__setattr__(self, n, np.asarray(v, dtype=np.float64).reshape(3))

    @property
    def has_pose(self) -> bool:
        return self.rvec is not None and self.tvec is not None

    def _pose(self) -> tuple[np.ndarray, np.ndarray]:
        if not self.has_pose:
            raise ConfigError("this camera has intrinsics only (no ground-plane pose); "
                              "add one with 'motiontrack calibrate ground --intrinsics CAMERA'")
        R, _ = cv2.Rodrigues(self.rvec)
        return R, self.tvec

    @property
    def center(self) -> np.ndarray:
        R, t = self._pose()
        return -R.T @ t

    @property
    def image_size(self) -> tuple[int, int]:
        return int(self.size[0]), int(self.size[1])

    def world_to_image(self, points: np.ndarray, distorted: bool = True) -> np.ndarray:
        """World points (N, 2|3) metres → (N, 2) pixels; NaN behind the camera."""
        P = _as_world(points)
        if len(P) == 0:
            return np.zeros((0, 2))
        R, t = self._pose()
        zc = P @ R[2] + t[2]
        dist = self.dist if distorted else np.zeros(5)
        px, _ = cv2.projectPoints(P.reshape(-1, 1, 3), self.rvec, self.tvec, self.K, dist)
        px = px.reshape(-1, 2).astype(np.float64)
        px[zc <= 0] = np.nan
        return px

    def rays(self, pixels: np.ndarray, distorted: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Pixels → world rays ``(origins (N, 3) metres, unit directions (N, 3))``."""
        px = _as_pixels(pixels)
        R, _ = self._pose()
        if len(px) == 0:
            return np.zeros((0, 3)), np.zeros((0, 3))
        dist = self.dist if distorted else np.zeros(5)
        # many more than OpenCV's default 5 iterations, for exact world <-> image round trips
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)
        n = cv2.undistortPoints(px.reshape(-1, 1, 2), self.K, dist, None, None, None,
                                crit).reshape(-1, 2)
        dc = np.hstack([n, np.ones((len(n), 1))])
        dw = dc @ R
        dw /= np.linalg.norm(dw, axis=1, keepdims=True)
        return np.broadcast_to(self.center, dw.shape).copy(), dw

    def image_to_world(self, pixels: np.ndarray, z: float = 0.0, distorted: bool = True) -> np.ndarray:
        """Pixels → (N, 2) world ``X, Y`` metres on ``Z = z``; NaN above the horizon."""
        o, d = self.rays(pixels, distorted=distorted)
        return _intersect_plane(o, d, z)

    def undistort(self, image: np.ndarray) -> np.ndarray:
        """Undistorted image with the same camera matrix ``K``."""
        m1, m2 = _undistort_maps(self, image.shape[0], image.shape[1])
        return cv2.remap(image, m1, m2, cv2.INTER_LINEAR)

    def resized(self, width: int, height: int) -> "OpenCVCamera":
        """The same camera for its video scaled to ``width`` x ``height`` pixels: ``K`` follows
        the pixel grid (:func:`~motiontrack.calibrate.tsai.pixel_scaling`); the distortion
        coefficients (of normalised coordinates) and the ground pose stay."""
        K = pixel_scaling(self.image_size, (width, height)) @ self.K
        return OpenCVCamera(K=K, dist=self.dist.copy(), size=(int(width), int(height)),
                            rvec=self.rvec, tvec=self.tvec, meta=dict(self.meta))


@functools.lru_cache(maxsize=8)
def _undistort_maps(cam: OpenCVCamera, h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """Remap tables of ``cv2.undistort`` (cached per camera object and size)."""
    return cv2.initUndistortRectifyMap(cam.K, cam.dist, None, cam.K, (w, h), cv2.CV_32FC1)


def parse_pattern(text: str) -> tuple[int, int]:
    """``"9x6"`` → ``(9, 6)`` inner corners per row and column."""
    try:
        c, r = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise ConfigError(f"pattern must look like 9x6 (inner corners), got {text!r}") from None
    if c < 2 or r < 2:
        raise ConfigError(f"pattern needs at least 2x2 inner corners, got {text!r}")
    if c > MAX_PATTERN_SIDE or r > MAX_PATTERN_SIDE:
        raise ConfigError(f"pattern must have at most {MAX_PATTERN_SIDE} inner corners per side, "
                          f"got {c if c > MAX_PATTERN_SIDE else r}")
    return c, r


#: most inner corners per side of a chessboard (printed boards have up to a few dozen)
MAX_PATTERN_SIDE = 100


def board_points(pattern: tuple[int, int], square: float) -> np.ndarray:
    """(cols*rows, 3) float32 corner positions on the board plane ``Z = 0`` (units of ``square``),
    in the row-major order of ``cv2.findChessboardCorners``."""
    cols, rows = pattern
    g = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2).astype(np.float32)
    return np.hstack([g * np.float32(square), np.zeros((len(g), 1), np.float32)])


def find_corners(gray: np.ndarray, pattern: tuple[int, int]) -> np.ndarray | None:
    """Inner corners (cols*rows, 2) float32 refined to sub-pixel, or ``None`` if not found."""
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    ok, corners = cv2.findChessboardCorners(gray, pattern, flags=flags)
    if not ok:
        return None
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 1e-4)
    corners = cv2.cornerSubPix(gray, corners, (11, 11), (-1, -1), crit)
    return corners.reshape(-1, 2)


@dataclass(frozen=True, eq=False)
class ChessboardResult:
    """Outcome of :func:`calibrate_chessboard`.

    Attributes
    ----------
    camera : OpenCVCamera
    rms : float
        Overall RMS reprojection error (pixels), as returned by ``cv2.calibrateCamera``.
    per_view : (V,) float64
        RMS reprojection error of each used view (pixels).
    used : tuple of str
        Names of the images in which the board was found (same order as ``per_view``).
    skipped : tuple of str
        Images without a detected board.
    other_size : tuple of str
        Images of another size than the calibration's (skipped).
    rvecs, tvecs : (V, 3) float64
        Board pose in each view (metres when ``square`` is in metres).
    """

    camera: OpenCVCamera
    rms: float
    per_view: np.ndarray
    used: tuple[str, ...]
    skipped: tuple[str, ...]
    rvecs: np.ndarray
    tvecs: np.ndarray
    pattern: tuple[int, int]
    square: float
    flags: int
    other_size: tuple[str, ...] = ()


def _common_size(images: Sequence[np.ndarray]) -> tuple[int, int]:
    """``(width, height)`` most of ``images`` have; the first such size on a tie."""
    sizes = [(int(im.shape[1]), int(im.shape[0])) for im in images]
    counts = Counter(sizes)
    return max(dict.fromkeys(sizes), key=lambda s: counts[s]) if sizes else (0, 0)


def calibrate_chessboard(images: Sequence[np.ndarray], pattern: tuple[int, int], square: float,
                         names: Sequence[str] | None = None,
                         flags: int = cv2.CALIB_FIX_ASPECT_RATIO) -> ChessboardResult:
    """Calibrate from chessboard photos.

    Parameters
    ----------
    images : sequence of (H, W[, 3]) uint8
        Photos of one camera. The calibration is at the size most of them share (the first such
        size on a tie); a photo of another size is skipped with a warning (a stray file a glob
        picked up, e.g. ``right.jpg`` beside ``right01.jpg``).
    pattern : (cols, rows)
        Inner corners per row and per column, e.g. ``(9, 6)``.
    square : float
        Side of one square (metres).
    flags : int
        ``cv2.calibrateCamera`` flags; the default fixes fx/fy to the initial aspect ratio 1, as
        in OpenCV's reference calibration of the sample images.

    Raises
    ------
    InputError
        When no image of the calibration's size contains the board.
    """
    if square <= 0 or not math.isfinite(square):
        raise ConfigError(f"square size must be > 0, got {square}")
    names = list(names) if names is not None else [f"image{i}" for i in range(len(images))]
    obj = board_points(pattern, square)
    obj_pts, img_pts, used, skipped, other_size = [], [], [], [], []
    size = _common_size(images)
    for img, name in zip(images, names):
        gray = to_gray(img)
        s = (gray.shape[1], gray.shape[0])
        if s != size:
            # one camera has one image size: a photo of another size is not of this camera (or
            # was resized) and its corners would not fit the same K
            log.warning("%s: image size %dx%d differs from %dx%d (most of the photos), skipped",
                        printable(name), *s, *size)
            other_size.append(name)
            continue
        c = find_corners(gray, pattern)
        if c is None:
            log.warning("%s: no %dx%d chessboard found, skipped", name, *pattern)
            skipped.append(name)
            continue
        obj_pts.append(obj)
        img_pts.append(c.reshape(-1, 1, 2).astype(np.float32))
        used.append(name)
    if not used:
        other = (f" ({len(other_size)} of another size than {size[0]}x{size[1]} skipped)"
                 if other_size else "")
        raise InputError(f"no {pattern[0]}x{pattern[1]} chessboard found in any of the "
                         f"{len(names)} image(s){other}; check --pattern (inner corners, e.g. 9x6)")
    K0 = np.eye(3)
    rms, K, dist, rvecs, tvecs = cv2.calibrateCamera(obj_pts, img_pts, size, K0, None, flags=flags)
    per_view = []
    for o, i, r, t in zip(obj_pts, img_pts, rvecs, tvecs):
        p, _ = cv2.projectPoints(o, r, t, K, dist)
        per_view.append(float(np.sqrt(np.mean(np.sum((p.reshape(-1, 2) - i.reshape(-1, 2)) ** 2,
                                                      axis=1)))))
    cam = OpenCVCamera(K=K, dist=dist.reshape(-1), size=size)
    return ChessboardResult(
        camera=cam, rms=float(rms), per_view=np.asarray(per_view), used=tuple(used),
        skipped=tuple(skipped), rvecs=np.asarray(rvecs, dtype=np.float64).reshape(-1, 3),
        tvecs=np.asarray(tvecs, dtype=np.float64).reshape(-1, 3), pattern=pattern,
        square=float(square), flags=int(flags), other_size=tuple(other_size),
    )


def write_opencv_yaml(path: str | Path, camera: OpenCVCamera,
                      result: ChessboardResult | None = None) -> None:
    """Write an OpenCV ``FileStorage`` YAML (atomically)."""
    path = Path(path)
    tmp = temp_path_for(path)
    try:
        fs = cv2.FileStorage(str(tmp), cv2.FILE_STORAGE_WRITE | cv2.FILE_STORAGE_FORMAT_YAML)
        fs.write("image_width", int(camera.size[0]))
        fs.write("image_height", int(camera.size[1]))
        if result is not None:
            fs.write("nframes", len(result.used))
            fs.write("board_width", int(result.pattern[0]))
            fs.write("board_height", int(result.pattern[1]))
            fs.write("square_size", float(result.square))
            fs.write("flags", int(result.flags))
        fs.write("camera_matrix", camera.K)
        fs.write("distortion_coefficients", camera.dist.reshape(-1, 1))
        if result is not None:
            fs.write("avg_reprojection_error", float(result.rms))
            fs.write("per_view_reprojection_errors", result.per_view.reshape(-1, 1))
            fs.write("extrinsic_parameters", np.hstack([result.rvecs, result.tvecs]))
        if camera.has_pose:
            fs.write("ground_rvec", camera.rvec.reshape(3, 1))
            fs.write("ground_tvec", camera.tvec.reshape(3, 1))
        fs.release()
        commit_temp(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def read_opencv_yaml(path: str | Path) -> OpenCVCamera:
    """Read ``camera_matrix``, ``distortion_coefficients``, image size and optional ground pose.

    The text is checked before OpenCV's ``FileStorage`` parses it (:func:`check_yaml_text`):
    OpenCV's parsers recurse on nesting and crash the process on a file nested thousands deep,
    and read XML content in a ``.yml`` file. Every node is checked for its kind and size before
    it is read, so a matrix of the wrong size (or one claiming 10**5 x 10**5 elements) is an
    :class:`InputError` naming it, not an OpenCV assertion or allocation.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"camera file not found: {location(p)}")
    check_yaml_text(p)
    where = f"OpenCV camera YAML {location(p)}"
    try:
        fs = cv2.FileStorage(str(p), cv2.FILE_STORAGE_READ)
    except (cv2.error, SystemError) as exc:
        raise InputError(f"malformed {where}: {_opencv_parse_message(exc)}") from None
    try:
        if not fs.isOpened() or not fs.root().isMap():
            raise InputError(f"malformed {where}: expected a mapping of names to values")
        K = _yaml_matrix(fs, "camera_matrix", where, lambda r, c: (r, c) == (3, 3), "3x3")
        dist = _yaml_matrix(fs, "distortion_coefficients", where,
                            lambda r, c: min(r, c) == 1 and r * c in _DIST_COUNTS,
                            f"1xN or Nx1 with N in {_DIST_COUNTS}")
        if K is None or dist is None:
            raise InputError(f"{location(p)}: needs camera_matrix and distortion_coefficients "
                             "matrices")
        w, h = (_yaml_side(fs, k, where) for k in ("image_width", "image_height"))
        three = (lambda r, c: r * c == 3 and min(r, c) == 1)
        rv = _yaml_matrix(fs, "ground_rvec", where, three, "3x1")
        tv = _yaml_matrix(fs, "ground_tvec", where, three, "3x1")
    except cv2.error as exc:
        raise InputError(f"malformed {where}: {_opencv_parse_message(exc)}") from None
    finally:
        fs.release()
    if (rv is None) != (tv is None):
        raise InputError(f"{where}: ground_rvec and ground_tvec go together; found only one")
    try:
        return OpenCVCamera(K=K, dist=dist.reshape(-1), size=(w, h),
                            rvec=None if rv is None else rv.reshape(3),
                            tvec=None if tv is None else tv.reshape(3))
    except ValueError as exc:
        raise InputError(f"invalid camera in {location(p)}: {exc}") from None


#: distortion coefficient counts OpenCV's models use
_DIST_COUNTS = (4, 5, 8, 12, 14)
#: largest OpenCV camera YAML read (a calibration with many views is a few hundred kB)
MAX_YAML_BYTES = 16 * 2**20
#: deepest nesting of sequences and mappings accepted (OpenCV's own files nest 2 deep)
MAX_YAML_DEPTH = 32
#: most flow brackets accepted: a bound on the nesting that holds however the text is quoted
#: (OpenCV's parsers read 20,000 levels and crash on 50,000; a camera file has a few)
MAX_YAML_BRACKETS = 1000


def check_yaml_text(path: Path) -> None:
    """Refuse, before OpenCV parses it, a camera YAML that is too large, not UTF-8 text, XML,
    or nested deeper than :data:`MAX_YAML_DEPTH` (OpenCV's parser recurses per level and a file
    nested 50,000 deep crashes the process with a segmentation fault)."""
    text = read_text(path, "OpenCV camera YAML", MAX_YAML_BYTES)
    if text.lstrip().startswith("<"):
        raise InputError(f"OpenCV camera YAML {location(path)}: XML content; expected the YAML "
                         "that 'motiontrack calibrate chessboard' writes")
    deep = _too_deep(text, MAX_YAML_DEPTH)
    if deep is not None:
        raise InputError(f"OpenCV camera YAML {location(path, *deep)}: nested deeper than "
                         f"{MAX_YAML_DEPTH} levels")
    brackets = text.count("[") + text.count("{")
    if brackets > MAX_YAML_BRACKETS:
        # whatever quotes and comments hide from _too_deep, no nesting can be deeper than this
        raise InputError(f"OpenCV camera YAML {location(path)}: {brackets} brackets '[' and '{{', "
                         f"more than the {MAX_YAML_BRACKETS} a camera file may have")


_YAML_SPECIAL = re.compile(r"[\[\]{}\"'#\\]")


def _too_deep(text: str, limit: int) -> tuple[int, int] | None:
    """``(line, column)`` (1-based) where the nesting of YAML text first exceeds ``limit``, or
    None. Counts flow brackets ``[ {`` outside quotes and comments, plus block nesting by
    indentation and ``- `` sequence entries; it over-counts brackets in plain scalars, which only
    makes it stricter."""
    flow = 0
    indents: list[int] = []
    quote = ""
    for lineno, line in enumerate(text.splitlines(), 1):
        if not quote and flow == 0:
            body = line.lstrip(" ")
            if not body or body.startswith("#"):
                continue
            indent = len(line) - len(body)
            while indents and indents[-1] >= indent:
                indents.pop()
            indents.append(indent)
            while body.startswith("- ") or body == "-":  # "- - x": a sequence in a sequence
                body = body[2:].lstrip(" ")
                indent += 2
                indents.append(indent)
        block = len(indents)
        escaped_at = -1
        for m in _YAML_SPECIAL.finditer(line):
            ch, col = m.group(), m.start() + 1
            if quote:
                if col == escaped_at:
                    pass
                elif ch == "\\" and quote == '"':
                    escaped_at = col + 1
                elif ch == quote:
                    quote = ""
            elif ch in "\"'":
                quote = ch
            elif ch == "#" and (col == 1 or line[col - 2] in " \t"):
                break
            elif ch in "[{":
                flow += 1
                if flow + block > limit:
                    return lineno, col
            elif ch in "]}":
                flow = max(0, flow - 1)
        if block > limit:
            return lineno, 1
    return None


def _opencv_parse_message(exc: Exception) -> str:
    """The useful part of an OpenCV persistence error: ``line N: what`` (OpenCV's parse messages
    are fixed texts, such as "Missing , between the elements", that quote nothing of the file)."""
    cause = exc.__cause__ or exc.__context__  # FileStorage() raises SystemError from cv2.error
    text = str(cause if isinstance(exc, SystemError) and cause is not None else exc)
    m = re.search(r"\((\d+)\): ([^'\n]*)'?\s*$", text)
    if m:
        return f"line {m.group(1)}: {printable(m.group(2).strip())[:120]}"
    m = re.search(r"error: \(([-\d]+):([^)]*)\)", text)
    return printable(m.group(2)) if m else "not a readable OpenCV file"


def _yaml_matrix(fs, key: str, where: str, shape_ok, shape: str) -> np.ndarray | None:
    """Matrix ``key`` of an open FileStorage, or None when absent; checked for kind, size and
    finite values before and after OpenCV reads it."""
    node = fs.getNode(key)
    if node.empty() or node.isNone():
        return None
    if not node.isMap():
        raise InputError(f"{where}: {key}: expected an OpenCV matrix (!!opencv-matrix with rows, "
                         "cols, dt and data)")
    rows, cols, data = node.getNode("rows"), node.getNode("cols"), node.getNode("data")
    if not (rows.isInt() and cols.isInt() and data.isSeq()):
        raise InputError(f"{where}: {key}: an OpenCV matrix needs integer rows and cols and a "
                         "data sequence")
    r, c = int(rows.real()), int(cols.real())
    if not shape_ok(r, c):
        raise InputError(f"{where}: {key}: expected a {shape} matrix, got {r}x{c}")
    if data.size() != r * c:
        raise InputError(f"{where}: {key}: a {r}x{c} matrix needs {r * c} values in data, got "
                         f"{data.size()}")
    m = node.mat()
    if m is None or m.size != r * c:
        raise InputError(f"{where}: {key}: not a single-channel {r}x{c} matrix")
    m = np.asarray(m, dtype=np.float64)
    if not np.isfinite(m).all():
        raise InputError(f"{where}: {key}: values must be finite numbers")
    return m


def _yaml_side(fs, key: str, where: str) -> int:
    """``image_width`` or ``image_height``: a whole number of pixels."""
    node = fs.getNode(key)
    if node.empty() or node.isNone():
        raise InputError(f"{where}: needs {key} (pixels)")
    v = node.real() if (node.isInt() or node.isReal()) else math.nan
    if not (math.isfinite(v) and v.is_integer() and 1 <= v <= MAX_IMAGE_SIDE):
        shown = f"{v:g}" if math.isfinite(v) else "no number"
        raise InputError(f"{where}: {key} must be a whole number of pixels in "
                         f"[1, {MAX_IMAGE_SIDE}], got {shown}")
    return int(v)
