"""Tsai's camera model (R. Y. Tsai 1987; thesis §2.1) with the PETS 2009 XML layout.

Model, following Tsai (1987) and R. Willson's reference implementation (``cal_tran.c``):

1. world → camera: ``P_c = R P_w + T`` with ``R = Rz(rz) · Ry(ry) · Rx(rx)`` (rotate about the world
   x axis first, then y, then z), i.e.::

       r1 = cb cg,  r2 = cg sa sb - ca sg,  r3 = sa sg + ca cg sb
       r4 = cb sg,  r5 = sa sb sg + ca cg,  r6 = ca sb sg - cg sa
       r7 = -sb,    r8 = cb sa,             r9 = ca cb

   with ``sa = sin rx, ca = cos rx, sb = sin ry, ...`` (Tsai eq. 2; Willson's ``calc_rr``).
2. perspective: ``Xu = f xc / zc``, ``Yu = f yc / zc`` (undistorted sensor coordinates, mm).
3. radial distortion: ``Xu = Xd (1 + κ1 r²)``, ``Yu = Yd (1 + κ1 r²)``, ``r² = Xd² + Yd²``
   (Tsai eq. 3). Removing it is closed form; adding it means solving the cubic
   ``κ1 rd³ + rd - ru = 0`` for ``rd`` (Newton's method here).
4. sensor → frame buffer: ``Xf = sx Xd / dpx + Cx``, ``Yf = Yd / dpy + Cy`` with
   ``dpx = dx ncx / nfx`` (Tsai eq. 4).

Units are those of the PETS files: millimetres (world, T, f, dx, dy) and radians; κ1 is in 1/mm².
:class:`TsaiCamera` converts to and from metres at its public ``image_to_world`` /
``world_to_image`` boundary (``unit = 1000`` mm per metre).
"""

from __future__ import annotations

import functools
import logging
import math
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from xml.etree.ElementTree import ParseError

import cv2
import defusedxml.ElementTree as ET
import numpy as np
import tomli_w
from defusedxml import DefusedXmlException

from ..errors import InputError, excerpt, location, printable
from ..io.atomic import atomic_write_text
from ..io.tomlfile import read_toml
from ..io.xmlsafe import unsafe_xml_reason

log = logging.getLogger(__name__)

__all__ = [
    "TsaiCamera",
    "tsai_rotation",
    "rotation_to_tsai_angles",
    "distort_sensor",
    "undistort_sensor",
    "read_tsai_xml",
    "write_tsai_xml",
    "read_tsai_toml",
    "write_tsai_toml",
    "pixel_scaling",
]


def tsai_rotation(rx: float, ry: float, rz: float) -> np.ndarray:
    """Rotation matrix of Tsai's angles (radians): ``R = Rz(rz) @ Ry(ry) @ Rx(rx)``.

    Returns
    -------
    (3, 3) float64, mapping world axes to camera axes (``P_c = R P_w + T``).
    """
    sa, ca = math.sin(rx), math.cos(rx)
    sb, cb = math.sin(ry), math.cos(ry)
    sg, cg = math.sin(rz), math.cos(rz)
    return np.array([
        [cb * cg, cg * sa * sb - ca * sg, sa * sg + ca * cg * sb],
        [cb * sg, sa * sb * sg + ca * cg, ca * sb * sg - cg * sa],
        [-sb, cb * sa, ca * cb],
    ], dtype=np.float64)


def rotation_to_tsai_angles(R: np.ndarray) -> tuple[float, float, float]:
    """Inverse of :func:`tsai_rotation` (``ry`` in [-π/2, π/2]); returns ``(rx, ry, rz)`` radians."""
    R = np.asarray(R, dtype=np.float64)
    ry = math.asin(max(-1.0, min(1.0, -R[2, 0])))
    cb = math.cos(ry)
    if abs(cb) > 1e-12:
        rx = math.atan2(R[2, 1], R[2, 2])
        rz = math.atan2(R[1, 0], R[0, 0])
    else:  # gimbal lock: only rx - rz (or rx + rz) is defined; choose rz = 0
        rz = 0.0
        rx = math.atan2(-R[1, 2], R[1, 1])
    return rx, ry, rz


def undistort_sensor(xd: np.ndarray, yd: np.ndarray, kappa1: float) -> tuple[np.ndarray, np.ndarray]:
    """Distorted → undistorted sensor coordinates (mm), closed form (Tsai eq. 3)."""
    xd = np.asarray(xd, dtype=np.float64)
    yd = np.asarray(yd, dtype=np.float64)
    k = 1.0 + kappa1 * (xd * xd + yd * yd)
    return xd * k, yd * k


def distort_sensor(xu: np.ndarray, yu: np.ndarray, kappa1: float,
                   iterations: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """Undistorted → distorted sensor coordinates (mm): solve ``κ1 rd³ + rd = ru`` for ``rd``.

    Newton's method from ``rd = ru``. For κ1 > 0 the cubic ``g(rd) = κ1 rd³ + rd - ru`` is increasing
    and convex on ``rd >= 0`` and ``g(ru) >= 0``, so the iterates decrease monotonically to the unique
    root (no cancellation problems for tiny κ1, unlike Cardano's formula). For κ1 < 0 radii beyond
    the turning point ``ru > 2 / (3 sqrt(-3 κ1))`` have no solution and give NaN.
    """
    xu = np.asarray(xu, dtype=np.float64)
    yu = np.asarray(yu, dtype=np.float64)
    ru = np.hypot(xu, yu)
    if kappa1 == 0.0 or ru.size == 0:
        return xu.copy(), yu.copy()
    if kappa1 < 0:
        valid = ru <= 2.0 / (3.0 * math.sqrt(-3.0 * kappa1))
        ru_ok = np.where(valid, ru, 0.0)
    else:
        valid = np.ones(ru.shape, dtype=bool)
        ru_ok = ru
    rd = ru_ok.copy()
    for _ in range(iterations):
        g = kappa1 * rd ** 3 + rd - ru_ok
        dg = 3.0 * kappa1 * rd ** 2 + 1.0
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(dg > 0, g / dg, 0.0)
        rd = rd - step
        if not np.any(np.abs(step) > 1e-15 * np.maximum(1.0, np.abs(rd))):
            break
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(ru > 0, rd / np.where(ru > 0, ru, 1.0), 1.0)
    scale = np.where(valid & np.isfinite(ru), scale, np.nan)
    return xu * scale, yu * scale


#: largest image width or height a camera file may give (pixels)
MAX_IMAGE_SIDE = 100_000

_GEOMETRY = ("width", "height", "ncx", "nfx", "dx", "dy", "dpx", "dpy")
_INTRINSIC = ("focal", "kappa1", "cx", "cy", "sx")
_EXTRINSIC = ("tx", "ty", "tz", "rx", "ry", "rz")


@dataclass(frozen=True)
class TsaiCamera:
    """A calibrated Tsai camera (PETS 2009 XML fields; mm, rad, pixels).

    Attributes
    ----------
    width, height : int
        Image size in pixels.
    ncx, nfx : float
        Sensor elements in x, pixels per line sampled by the frame grabber.
    dx, dy : float
        Centre-to-centre distance of sensor elements (mm).
    dpx, dpy : float
        Effective pixel size (mm); ``dpx = dx ncx / nfx``.
    focal : float
        Effective focal length f (mm).
    kappa1 : float
        First radial distortion coefficient (1/mm²).
    cx, cy : float
        Principal point (pixels).
    sx : float
        Horizontal scale uncertainty factor.
    tx, ty, tz : float
        Translation (mm), world → camera.
    rx, ry, rz : float
        Tsai rotation angles (rad), see :func:`tsai_rotation`.
    unit : float
        World length units per metre (1000 for the mm of the PETS files).
    """

    width: int
    height: int
    ncx: float
    nfx: float
    dx: float
    dy: float
    dpx: float
    dpy: float
    focal: float
    kappa1: float
    cx: float
    cy: float
    sx: float
    tx: float
    ty: float
    tz: float
    rx: float
    ry: float
    rz: float
    unit: float = 1000.0

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"Tsai parameter {f.name} must be a finite number, got {v!r}")
        for name in ("width", "height", "dpx", "dpy", "focal", "sx", "unit"):
            if getattr(self, name) <= 0:
                raise ValueError(f"Tsai parameter {name} must be > 0, got {getattr(self, name)}")

    # -- derived quantities ----------------------------------------------------------------------
    @property
    def R(self) -> np.ndarray:
        """(3, 3) world → camera rotation."""
        return tsai_rotation(self.rx, self.ry, self.rz)

    @property
    def T(self) -> np.ndarray:
        """(3,) translation in model units (mm)."""
        return np.array([self.tx, self.ty, self.tz], dtype=np.float64)

    @property
    def center(self) -> np.ndarray:
        """(3,) camera centre in world coordinates, metres: ``-Rᵀ T``."""
        return -(self.R.T @ self.T) / self.unit

    @property
    def image_size(self) -> tuple[int, int]:
        return int(self.width), int(self.height)

    # -- pixel <-> sensor ------------------------------------------------------------------------
    def _pixels_to_sensor(self, px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        xd = self.dpx * (px[:, 0] - self.cx) / self.sx
        yd = self.dpy * (px[:, 1] - self.cy)
        return xd, yd

    def _sensor_to_pixels(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return np.stack([x * self.sx / self.dpx + self.cx, y / self.dpy + self.cy], axis=1)

    # -- projections -----------------------------------------------------------------------------
    def world_to_image(self, points: np.ndarray, distorted: bool = True) -> np.ndarray:
        """Project world points (metres) into the image.

        Parameters
        ----------
        points : (N, 2) or (N, 3) float
            World ``X, Y`` (on ``Z = 0``) or ``X, Y, Z`` in metres.
        distorted : bool
            ``True`` for pixels of the recorded (distorted) image, ``False`` for the undistorted
            image produced by :meth:`undistort`.

        Returns
        -------
        (N, 2) float64 pixels; NaN for points behind the camera.
        """
        P = _as_world(points) * self.unit
        pc = P @ self.R.T + self.T
        with np.errstate(divide="ignore", invalid="ignore"):
            zc = np.where(pc[:, 2] > 0, pc[:, 2], np.nan)
            xu = self.focal * pc[:, 0] / zc
            yu = self.focal * pc[:, 1] / zc
        if distorted:
            xu, yu = distort_sensor(xu, yu, self.kappa1)
        return self._sensor_to_pixels(xu, yu)

    def rays(self, pixels: np.ndarray, distorted: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Back-project pixels to rays in the world: origin (camera centre) and unit direction.

        Returns
        -------
        origins, directions : (N, 3) float64, metres / unit vectors.
        """
        px = _as_pixels(pixels)
        xs, ys = self._pixels_to_sensor(px)
        if distorted:
            xs, ys = undistort_sensor(xs, ys, self.kappa1)
        dc = np.stack([xs, ys, np.full_like(xs, self.focal)], axis=1)
        dw = dc @ self.R  # Rᵀ d for each row
        dw /= np.linalg.norm(dw, axis=1, keepdims=True) if len(dw) else 1.0
        return np.broadcast_to(self.center, dw.shape).copy(), dw

    def image_to_world(self, pixels: np.ndarray, z: float = 0.0, distorted: bool = True) -> np.ndarray:
        """Pixels → world points (metres) on the horizontal plane ``Z = z`` (metres).

        Returns
        -------
        (N, 2) float64 ``X, Y`` metres; NaN where the ray does not hit the plane in front of the
        camera (above the horizon).
        """
        o, d = self.rays(pixels, distorted=distorted)
        return _intersect_plane(o, d, z)

    def undistort(self, image: np.ndarray) -> np.ndarray:
        """Remove radial distortion: the image a distortion-free Tsai camera would record.

        The remap tables are cached per camera and image size, so calling this per video frame
        costs one ``cv2.remap``.
        """
        mx, my = _undistort_maps(self, image.shape[0], image.shape[1])
        return cv2.remap(image, mx, my, interpolation=cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT)

    def resized(self, width: int, height: int) -> "TsaiCamera":
        """The same camera for its video scaled to ``width`` x ``height`` pixels (a resized
        copy): the frame grabber samples ``width / self.width`` as many pixels per line
        (``nfx``), so the effective pixel size ``dpx = dx ncx / nfx`` grows by the inverse, as
        does ``dpy``, and the principal point moves with the pixel grid (:func:`pixel_scaling`).
        The sensor (``ncx``, ``dx``, ``dy``), the lens (``focal``, ``kappa1``), ``sx`` and the
        pose are the same camera's."""
        kx, ky = width / self.width, height / self.height
        A = pixel_scaling((self.width, self.height), (width, height))
        return replace(self, width=int(width), height=int(height), nfx=self.nfx * kx,
                       dpx=self.dpx / kx, dpy=self.dpy / ky, cx=A[0, 0] * self.cx + A[0, 2],
                       cy=A[1, 1] * self.cy + A[1, 2])

    def to_dict(self) -> dict[str, float]:
        return asdict(self)


def pixel_scaling(size: tuple[int, int], new_size: tuple[int, int]) -> np.ndarray:
    """(3, 3) map of pixel coordinates of an image of ``size`` (width, height) to those of the
    same image resized to ``new_size``, pixel centres at whole numbers (OpenCV's convention,
    and ``cv2.resize``'s): ``x' = (x + 0.5) kx - 0.5`` with ``kx = new width / width``."""
    kx, ky = new_size[0] / size[0], new_size[1] / size[1]
    return np.array([[kx, 0.0, 0.5 * kx - 0.5], [0.0, ky, 0.5 * ky - 0.5], [0.0, 0.0, 1.0]])


@functools.lru_cache(maxsize=8)
def _undistort_maps(cam: TsaiCamera, h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """For each pixel of the undistorted image, where to sample the recorded one (float32 maps)."""
    xs, ys = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    px = np.stack([xs.ravel(), ys.ravel()], axis=1)
    xu, yu = cam._pixels_to_sensor(px)
    xd, yd = distort_sensor(xu, yu, cam.kappa1)
    src = cam._sensor_to_pixels(xd, yd).astype(np.float32)
    return src[:, 0].reshape(h, w), src[:, 1].reshape(h, w)


def _as_world(points) -> np.ndarray:
    P = np.asarray(points, dtype=np.float64)
    if P.size == 0:
        return np.zeros((0, 3))
    P = P.reshape(-1, P.shape[-1]) if P.ndim > 1 else P.reshape(1, -1)
    if P.shape[1] == 2:
        P = np.hstack([P, np.zeros((len(P), 1))])
    if P.shape[1] != 3:
        raise ValueError(f"world points must have shape (N, 2) or (N, 3), got {P.shape}")
    return P


def _as_pixels(points) -> np.ndarray:
    P = np.asarray(points, dtype=np.float64)
    if P.size == 0:
        return np.zeros((0, 2))
    P = P.reshape(-1, 2) if P.ndim > 1 else P.reshape(1, -1)
    if P.shape[1] != 2:
        raise ValueError(f"image points must have shape (N, 2), got {P.shape}")
    return P


def _intersect_plane(origins: np.ndarray, dirs: np.ndarray, z: float = 0.0) -> np.ndarray:
    """Intersect rays with the plane ``Z = z``; (N, 2) X, Y, NaN when parallel or behind."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (z - origins[:, 2]) / dirs[:, 2]
    t = np.where(t > 0, t, np.nan)
    return origins[:, :2] + t[:, None] * dirs[:, :2]


# -- file formats --------------------------------------------------------------------------------
def read_tsai_xml(path: str | Path) -> TsaiCamera:
    """Read a PETS 2009 / Tsai calibration XML (``<Camera><Geometry/><Intrinsic/><Extrinsic/>``)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"camera file not found: {location(p)}")
    try:
        root = ET.parse(p).getroot()
    except DefusedXmlException as exc:
        raise InputError(f"refusing to parse camera XML {location(p)}: "
                         f"{unsafe_xml_reason(exc)}") from None
    except ParseError as exc:
        # expat's message ("not well-formed (invalid token): line 1, column 5") quotes nothing
        raise InputError(f"malformed Tsai camera XML {location(p)}: {printable(exc)}") from None
    except (ValueError, LookupError) as exc:  # e.g. an unknown encoding in the declaration
        raise InputError(f"malformed Tsai camera XML {location(p)} ({type(exc).__name__})") \
            from None
    values: dict[str, float] = {}
    for tag, names in (("Geometry", _GEOMETRY), ("Intrinsic", _INTRINSIC), ("Extrinsic", _EXTRINSIC)):
        el = root.find(tag)
        if el is None:
            raise InputError(f"malformed Tsai camera XML {location(p)}: missing <{tag}> element")
        for n in names:
            if n not in el.attrib:
                raise InputError(f"malformed Tsai camera XML {location(p)}: <{tag}> has no "
                                 f"attribute {n!r}")
            try:
                values[n] = float(el.attrib[n])
            except ValueError:
                raise InputError(f"malformed Tsai camera XML {location(p)}: <{tag} "
                                 f"{n}={excerpt(el.attrib[n])}> is not a number") from None
    return _tsai_camera(values, str(p))


def _tsai_camera(values: dict, name: str, unit: float = 1000.0) -> TsaiCamera:
    """:class:`TsaiCamera` from a file's values, :class:`InputError` naming the bad one: every
    value a finite number (not a boolean), width and height whole numbers of pixels in
    ``[1, MAX_IMAGE_SIDE]``."""
    for n, v in values.items():
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise InputError(f"invalid Tsai camera {location(name)}: {n} must be a number, got "
                             f"{_kind(v)}")
        if not abs(v) < 1e300:  # also NaN; and an integer too large for a float
            shown = v if isinstance(v, float) else f"an integer of {len(str(abs(v)))} digits"
            raise InputError(f"invalid Tsai camera {location(name)}: {n} must be a finite number "
                             f"(below 1e300), got {shown}")
    for n in ("width", "height"):
        v = values[n]
        if not (float(v).is_integer() and 1 <= v <= MAX_IMAGE_SIDE):
            raise InputError(f"invalid Tsai camera {location(name)}: {n} must be a whole number "
                             f"of pixels in [1, {MAX_IMAGE_SIDE}], got {v}")
        values[n] = int(v)
    try:
        return TsaiCamera(**values, unit=unit)
    except ValueError as exc:
        raise InputError(f"invalid Tsai camera {location(name)}: {exc}") from None


def _kind(v: object) -> str:
    """A value from a camera file for a message: text as a short excerpt, others by kind."""
    if v is None:
        return "nothing"
    if isinstance(v, str):
        return excerpt(v)
    if isinstance(v, bool):
        return repr(v).lower()
    if isinstance(v, (int, float)):
        return f"{v:g}" if isinstance(v, float) or abs(v) < 10**20 else "a longer integer"
    return {dict: "a table", list: "an array"}.get(type(v), f"a {type(v).__name__}")


def write_tsai_xml(cam: TsaiCamera, path: str | Path, name: str = "camera") -> None:
    """Write the PETS 2009 XML layout (atomically)."""
    def attrs(names):
        return " ".join(f'{n}="{getattr(cam, n):.10e}"' if n not in ("width", "height")
                        else f'{n}="{getattr(cam, n)}"' for n in names)
    text = (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        f'<Camera name="{name}">\n'
        f"\t<Geometry {attrs(_GEOMETRY)}/>\n"
        f"\t<Intrinsic {attrs(('focal', 'kappa1', 'cx', 'cy', 'sx'))}/>\n"
        f"\t<Extrinsic {attrs(_EXTRINSIC)}/>\n"
        "</Camera>\n"
    )
    atomic_write_text(path, text)


def write_tsai_toml(cam: TsaiCamera, path: str | Path) -> None:
    """Write our TOML layout: ``model = "tsai"`` and tables geometry / intrinsic / extrinsic."""
    doc = {
        "model": "tsai",
        "units": {"length": "mm", "angle": "rad", "unit_per_metre": cam.unit},
        "geometry": {n: getattr(cam, n) for n in _GEOMETRY},
        "intrinsic": {n: getattr(cam, n) for n in _INTRINSIC},
        "extrinsic": {n: getattr(cam, n) for n in _EXTRINSIC},
    }
    atomic_write_text(path, tomli_w.dumps(doc))


def tsai_from_toml_doc(doc: dict, name: str) -> TsaiCamera:
    """A :class:`TsaiCamera` from our TOML layout (see :func:`write_tsai_toml`); every table and
    value is checked, and a bad one is an :class:`InputError` naming it."""
    where = location(name)
    values: dict[str, float] = {}
    for table, names in (("geometry", _GEOMETRY), ("intrinsic", _INTRINSIC), ("extrinsic", _EXTRINSIC)):
        t = doc.get(table)
        if not isinstance(t, dict):
            raise InputError(f"{where}: missing [{table}] table for a Tsai camera")
        unknown = sorted(set(t) - set(names))
        if unknown:
            raise InputError(f"{where}: unknown keys in [{table}]: "
                             f"{', '.join(excerpt(k) for k in unknown[:5])}; valid keys: "
                             f"{', '.join(names)}")
        for n in names:
            if n not in t:
                raise InputError(f"{where}: [{table}] has no {n!r}")
            values[n] = t[n]
    units = doc.get("units", {})
    if not isinstance(units, dict):
        raise InputError(f"{where}: units must be a table (length, angle, unit_per_metre), got "
                         f"{_kind(units)}")
    unit = units.get("unit_per_metre", 1000.0)
    if isinstance(unit, bool) or not isinstance(unit, (int, float)) or not (
            math.isfinite(unit) and unit > 0):
        raise InputError(f"{where}: units.unit_per_metre must be a finite number > 0, got "
                         f"{unit if isinstance(unit, float) else _kind(unit)}")
    return _tsai_camera(values, name, unit=float(unit))


def read_tsai_toml(path: str | Path) -> TsaiCamera:
    return tsai_from_toml_doc(read_toml(path, "camera TOML"), str(path))
