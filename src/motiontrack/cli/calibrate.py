"""``motiontrack calibrate``: chessboard, thesis line method, ground plane, visual check."""

from __future__ import annotations

import argparse
import logging
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Callable, TextIO

from ._common import checked_max_pixels, max_pixels_option
from ..errors import (ConfigError, InputError, check_output_path, excerpt, finite_number, location,
                      require_file)

if TYPE_CHECKING:  # NumPy loads when a calibration command runs, not with every command
    import numpy as np

log = logging.getLogger(__name__)


def register(subparsers) -> None:
    p = subparsers.add_parser("calibrate", help="camera calibration (chessboard, lines, ground plane)",
                              description="Calibrate a camera and check the calibration.")
    sub = p.add_subparsers(dest="calibrate_command", metavar="METHOD",
                          help="calibration method, or show to check a calibration")
    p.set_defaults(func=lambda args: (p.print_help(), 2)[1])

    c = sub.add_parser("chessboard", help="OpenCV calibration from chessboard photos")
    c.add_argument("images", nargs="+", type=Path,
                   help="photos of the chessboard: files or glob patterns ('left*.jpg', "
                        "quoted or not)")
    c.add_argument("--pattern", default="9x6", help="inner corners per row x per column (9x6)")
    c.add_argument("--square", type=float, default=0.025, help="square side in metres (0.025)")
    c.add_argument("--free-aspect", action="store_true",
                   help="estimate fx and fy independently (default: fixed aspect ratio)")
    c.add_argument("-o", "--output", type=Path, required=True,
                   help="camera YAML to write (- for standard output)")
    c.add_argument("--force", action="store_true", help="overwrite an existing output")
    max_pixels_option(c)
    c.set_defaults(func=_locked(cmd_chessboard))

    s = sub.add_parser("show", help="undistorted image with the projected ground grid")
    s.add_argument("camera", type=Path, help="camera file (.xml Tsai, .yml OpenCV, .toml)")
    s.add_argument("image", type=Path, help="image, or a video (its first frame is used)")
    s.add_argument("-o", "--output", type=Path, required=True,
                   help="PNG/JPEG to write (- for a PNG on standard output)")
    s.add_argument("--step", type=float, default=None, help="grid spacing in metres (auto)")
    s.add_argument("--extent", default=None, help="grid extent xmin,xmax,ymin,ymax in metres (auto)")
    s.add_argument("--force", action="store_true", help="overwrite an existing output")
    max_pixels_option(s)
    s.set_defaults(func=_locked(cmd_show))

    ln = sub.add_parser("lines", help="thesis method: κ1 from straight lines + coplanar Tsai fit")
    ln.add_argument("image", type=Path, help="image of a grid of straight lines on the ground")
    ln.add_argument("--lines", type=Path, required=True,
                    help="CSV line,axis,value,u,v: rough image points (u, v px) of each line; axis x "
                         "(line X = value m), y (Y = value m) or - (straight only, for κ1)")
    ln.add_argument("--geometry", type=Path, default=None,
                    help="Tsai camera file whose Geometry (dpx, dpy, Cx, Cy, sx) is used")
    ln.add_argument("--pixel-mm", type=float, default=0.01,
                    help="pixel size in mm when no --geometry (0.01)")
    ln.add_argument("--mode", choices=("ridge", "edge"), default="ridge",
                    help="what marks a line: ridge (a thin painted line, the intensity extremum) or "
                         "edge (a step, the gradient extremum) (ridge)")
    ln.add_argument("--polarity", choices=("dark", "bright"), default="dark",
                    help="a ridge darker or brighter than its surroundings (dark; ignored by edge)")
    ln.add_argument("--half-width", type=float, default=6.0, help="normal search distance (px)")
    ln.add_argument("--fit-center", action="store_true", help="also estimate Cx, Cy")
    ln.add_argument("-o", "--output", type=Path, required=True,
                    help="camera .toml or .xml to write (- for TOML on standard output)")
    ln.add_argument("--force", action="store_true", help="overwrite an existing output")
    max_pixels_option(ln)
    ln.set_defaults(func=_locked(cmd_lines))

    g = sub.add_parser("ground", help="ground plane from image <-> world point pairs")
    g.add_argument("--points", type=Path, required=True, help="CSV u,v,x,y (pixels, metres)")
    g.add_argument("--intrinsics", type=Path, default=None,
                   help="OpenCV camera YAML: fit a full pose (solvePnP) instead of a homography")
    g.add_argument("--size", default=None, help="image size WxH (informative)")
    g.add_argument("-o", "--output", type=Path, required=True,
                   help="ground.toml (homography) or camera .yml (with --intrinsics); - for "
                        "standard output")
    g.add_argument("--force", action="store_true", help="overwrite an existing output")
    g.set_defaults(func=_locked(cmd_ground))




def _locked(command: Callable[[argparse.Namespace], int]) -> Callable[[argparse.Namespace], int]:
    """``command`` run holding the lock of its output's folder, as every command writing into a
    folder does: a second writer there is refused at once, and what a killed writer left of the
    output is removed first."""

    def run(args: argparse.Namespace) -> int:
        from ..io.atomic import writing_outputs

        check_output_path(args.output, "-o")
        with writing_outputs([args.output], force=True):   # --force is checked by the command
            return command(args)

    return run


def _check_out(path: Path, force: bool) -> None:
    """An existing output only with ``--force`` (:func:`_locked` checked the path itself)."""
    from ..io.atomic import check_writable

    check_writable([path], force)


def _positive(value: float | None, flag: str, hi: float, unit: str) -> None:
    """A float option: finite, > 0 and at most ``hi`` (argparse takes "nan" and "inf")."""
    if value is not None and not 0 < value <= hi:
        raise ConfigError(f"{flag} must be a number in (0, {hi:g}] {unit}, got {value}")


def _messages(args: argparse.Namespace) -> TextIO:
    """Where a command's report goes: standard error when its result goes to standard output
    (``-o -``)."""
    from ..io.atomic import is_stdout

    return sys.stderr if is_stdout(args.output) else sys.stdout


def _suffix(path: Path, default: str) -> str:
    """The output's suffix in lower case, which chooses its format; ``default`` for standard
    output (``-``)."""
    from ..io.atomic import is_stdout

    return default if is_stdout(path) else path.suffix.lower()


def _read_image(path: Path, max_pixels: int, gray: bool = False) -> np.ndarray:
    """A picture, or a video's first frame; either refused before decoding when it has more
    than ``max_pixels`` pixels."""
    import cv2

    from ..io.imagesize import check_frame_size, check_image

    require_file(path, "image")
    check_image(path, max_pixels, "--max-pixels N")
    img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE if gray else cv2.IMREAD_COLOR)
    if img is None:  # maybe a video: take its first frame
        cap = cv2.VideoCapture(str(path))
        try:
            check_frame_size(str(path), int(cap.get(cv2.CAP_PROP_FRAME_WIDTH) or 0),
                             int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT) or 0), max_pixels,
                             "--max-pixels N")
            ok, img = cap.read()
        finally:
            cap.release()
        if not ok or img is None:
            raise InputError(f"cannot read an image or video frame from {path}")
        if gray:
            img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    return img


def cmd_chessboard(args: argparse.Namespace) -> int:
    import cv2
    import numpy as np

    from ..calibrate.chessboard import calibrate_chessboard, parse_pattern, write_opencv_yaml

    from ..io.paths import expand_paths

    pattern = parse_pattern(args.pattern)
    _positive(args.square, "--square", 10.0, "metres")
    _check_out(args.output, args.force)
    most = checked_max_pixels(args)
    args.images = expand_paths(args.images, "images")
    images = [_read_image(p, most) for p in args.images]
    flags = 0 if args.free_aspect else cv2.CALIB_FIX_ASPECT_RATIO
    res = calibrate_chessboard(images, pattern, args.square, [str(p) for p in args.images], flags)
    write_opencv_yaml(args.output, res.camera, res)
    K = res.camera.K
    print(f"views used: {len(res.used)} of {len(args.images)}; RMS reprojection error "
          f"{res.rms:.4f} px", file=_messages(args))
    print(f"fx={K[0, 0]:.3f} fy={K[1, 1]:.3f} cx={K[0, 2]:.3f} cy={K[1, 2]:.3f} "
          f"dist={np.array2string(res.camera.dist, precision=5)}", file=_messages(args))
    for name, e in zip(res.used, res.per_view):
        print(f"  {name}: {e:.4f} px", file=_messages(args))
    for name in res.skipped:
        print(f"  {name}: board not found (skipped)", file=_messages(args))
    w, h = res.camera.size
    for name in res.other_size:
        print(f"  {name}: not {w}x{h} like the others (skipped)", file=_messages(args))
    print(f"wrote {args.output}", file=_messages(args))
    return 0


def _nice_step(span: float) -> float:
    raw = span / 20.0
    e = 10 ** math.floor(math.log10(raw)) if raw > 0 else 1.0
    for m in (1, 2, 5, 10):
        if raw <= m * e:
            return m * e
    return 10 * e


def grid_overlay(camera, image: np.ndarray, step: float | None = None,
                 extent: tuple[float, float, float, float] | None = None) -> np.ndarray:
    """Undistorted copy of ``image`` with the ground grid ``Z = 0`` (metres) drawn on it."""
    import cv2
    import numpy as np

    out = camera.undistort(image)
    if out.ndim == 2:
        out = cv2.cvtColor(out, cv2.COLOR_GRAY2BGR)
    h, w = out.shape[:2]
    if getattr(camera, "has_pose", True) is False:
        log.warning("camera has no ground-plane pose: writing the undistorted image without a grid")
        return out
    if extent is None:
        us, vs = np.meshgrid(np.linspace(0, w - 1, 40), np.linspace(0, h - 1, 40))
        world = camera.image_to_world(np.stack([us.ravel(), vs.ravel()], 1))
        world = world[np.all(np.isfinite(world), axis=1)]
        if len(world) < 4:
            raise InputError("the ground plane is not visible in this camera view")
        lo = np.percentile(world, 5, axis=0)
        hi = np.percentile(world, 95, axis=0)
        # a view up to the horizon reaches far: keep the grid within the largest extent
        lo, hi = np.clip(lo, -MAX_EXTENT_M, MAX_EXTENT_M), np.clip(hi, -MAX_EXTENT_M, MAX_EXTENT_M)
        extent = (lo[0], hi[0], lo[1], hi[1])
    x0, x1, y0, y1 = _check_extent(extent)
    step = step or _nice_step(max(x1 - x0, y1 - y0))
    _positive(step, "--step", MAX_EXTENT_M, "metres")
    n = max((math.ceil(x1 / step) - math.floor(x0 / step) + 1),
            (math.ceil(y1 / step) - math.floor(y0 / step) + 1))
    if n > MAX_GRID_LINES:
        raise ConfigError(f"--step {step:g} m draws {n} grid lines across the extent, more than "
                          f"{MAX_GRID_LINES}; use a larger --step or a smaller --extent")
    xs = np.arange(math.floor(x0 / step), math.ceil(x1 / step) + 1) * step
    ys = np.arange(math.floor(y0 / step), math.ceil(y1 / step) + 1) * step
    t = np.linspace(0, 1, 300)
    lines = [(np.stack([np.full_like(t, x), ys[0] + (ys[-1] - ys[0]) * t], 1), x) for x in xs]
    lines += [(np.stack([xs[0] + (xs[-1] - xs[0]) * t, np.full_like(t, y)], 1), y) for y in ys]
    for k, (seg, v) in enumerate(lines):
        px = camera.world_to_image(seg, distorted=False)
        axis = abs(v) < step * 1e-6
        colour = ((0, 0, 255) if k < len(xs) else (0, 200, 0)) if axis else (0, 255, 255)
        ok = np.all(np.isfinite(px), axis=1) & (np.abs(px) < 4 * max(w, h)).all(axis=1)
        for a, b, oa, ob in zip(px[:-1], px[1:], ok[:-1], ok[1:]):
            if oa and ob:
                cv2.line(out, (int(round(a[0] * 16)), int(round(a[1] * 16))),
                         (int(round(b[0] * 16)), int(round(b[1] * 16))), colour, 2 if axis else 1,
                         cv2.LINE_AA, shift=4)
    cv2.putText(out, f"ground grid {step:g} m (X=0 red, Y=0 green)", (8, 20),
                cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
    return out


#: most grid lines ``calibrate show`` draws along each axis (each is 300 projected points)
MAX_GRID_LINES = 1000
#: largest grid extent coordinate (metres)
MAX_EXTENT_M = 1e6


def _check_extent(extent: tuple[float, ...]) -> tuple[float, float, float, float]:
    """``xmin, xmax, ymin, ymax`` finite, within ±:data:`MAX_EXTENT_M` and each min < max."""
    x0, x1, y0, y1 = (float(v) for v in extent)
    if not all(abs(v) <= MAX_EXTENT_M for v in (x0, x1, y0, y1)):  # also refuses NaN
        raise ConfigError(f"the grid extent must be finite numbers within ±{MAX_EXTENT_M:g} m, "
                          f"got {x0:g},{x1:g},{y0:g},{y1:g}")
    if not (x0 < x1 and y0 < y1):
        raise ConfigError(f"the grid extent must be xmin,xmax,ymin,ymax with xmin < xmax and "
                          f"ymin < ymax, got {x0:g},{x1:g},{y0:g},{y1:g}")
    return x0, x1, y0, y1


def cmd_show(args: argparse.Namespace) -> int:
    import cv2

    from ..calibrate.camera import load_camera
    from ..io.atomic import atomic_write_bytes

    _positive(args.step, "--step", MAX_EXTENT_M, "metres")
    camera = load_camera(args.camera)
    image = _read_image(args.image, checked_max_pixels(args))
    size = getattr(camera, "image_size", None)
    if size and tuple(size) != (image.shape[1], image.shape[0]):
        log.warning("image is %dx%d but the camera was calibrated for %dx%d", image.shape[1],
                    image.shape[0], *size)
    extent = None
    if args.extent:
        try:
            extent = tuple(float(v) for v in args.extent.split(","))
        except ValueError:
            extent = ()
        if len(extent) != 4:
            raise ConfigError(f"--extent must be xmin,xmax,ymin,ymax, got {args.extent!r}")
        extent = _check_extent(extent)
    _check_out(args.output, args.force)
    out = grid_overlay(camera, image, args.step, extent)
    ext = _suffix(args.output, ".png") or ".png"
    ok, buf = cv2.imencode(ext, out)
    if not ok:
        raise ConfigError(f"cannot encode an image as {ext!r}; use .png or .jpg")
    atomic_write_bytes(args.output, buf.tobytes())
    print(f"wrote {args.output}", file=_messages(args))
    return 0


def read_lines_csv(path: Path) -> list[tuple[str, str, float, np.ndarray]]:
    """``line,axis,value,u,v`` rows → ``[(name, axis, value, points (M, 2))]`` in file order.

    ``value`` is NaN for axis ``-`` (straight only); every number is finite. Errors name the
    line and column and quote at most a short excerpt of the offending field.
    """
    import numpy as np

    from ..calibrate.ground import read_csv_fields

    groups: dict[str, tuple[str, float, list]] = {}
    for lineno, fields in read_csv_fields(path, "lines file"):
        if not fields or not fields[0][1] or fields[0][1].startswith("#"):
            continue
        if lineno == 1 and fields[0][1].lower() == "line":
            continue
        if len(fields) != 5:
            raise InputError(f"{location(path, lineno)}: expected line,axis(x|y|-),value,u,v, got "
                             f"{len(fields)} fields")
        (_, name), (col, axis) = fields[0], fields[1]
        if axis.lower() not in ("x", "y", "-"):
            raise InputError(f"{location(path, lineno, col)}: expected line,axis(x|y|-),value,u,v: "
                             f"axis must be x, y or -, got {excerpt(axis)}")
        axis = axis.lower()
        value = math.nan if axis == "-" else _csv_number(path, lineno, fields[2])
        u, v = _csv_number(path, lineno, fields[3]), _csv_number(path, lineno, fields[4])
        first_axis, _, pts = groups.setdefault(name, (axis, value, []))
        if first_axis != axis:
            raise InputError(f"{location(path, lineno, col)}: line {excerpt(name)} changes axis")
        pts.append((u, v))
    out = [(k, a, val, np.asarray(p, dtype=np.float64)) for k, (a, val, p) in groups.items()]
    if not out:
        raise InputError(f"{location(path)}: no lines")
    return out


def _csv_number(path: Path, lineno: int, field: tuple[int, str]) -> float:
    """A finite number from a CSV field ``(column, text)`` (:func:`finite_number`)."""
    col, text = field
    return finite_number(text, location(path, lineno, col))


#: longest search along a line's normal, ``calibrate lines --half-width`` (pixels)
MAX_HALF_WIDTH_PX = 200.0


def cmd_lines(args: argparse.Namespace) -> int:
    import numpy as np

    from ..calibrate.camera import load_camera
    from ..calibrate.lines import (SensorGeometry, estimate_kappa1, fit_coplanar_tsai,
                                   intersect_grid, refine_line_points)
    from ..calibrate.tsai import TsaiCamera, write_tsai_toml, write_tsai_xml

    if _suffix(args.output, ".toml") not in (".toml", ".xml"):
        raise ConfigError(f"output must be .toml or .xml, got {args.output}")
    _positive(args.half_width, "--half-width", MAX_HALF_WIDTH_PX, "pixels")
    _check_out(args.output, args.force)
    gray = _read_image(args.image, checked_max_pixels(args), gray=True)
    h, w = gray.shape
    if args.geometry is not None:
        cam0 = load_camera(args.geometry)
        if not isinstance(cam0, TsaiCamera):
            raise InputError(f"{args.geometry}: --geometry needs a Tsai camera (.xml or .toml)")
        geom = SensorGeometry.from_camera(cam0)
    else:
        _positive(args.pixel_mm, "--pixel-mm", 1.0, "mm")
        geom = SensorGeometry.default(w, h, args.pixel_mm)
    spec = read_lines_csv(args.lines)
    refined = []
    for name, axis, value, pts in spec:
        if len(pts) < 2:
            raise InputError(f"{location(args.lines)}: line {excerpt(name)} needs at least 2 "
                             "points")
        r = refine_line_points(gray, pts, half_width=args.half_width, mode=args.mode,
                               polarity=args.polarity)
        if len(r) < 3:
            raise InputError(f"line {excerpt(name)}: no {args.polarity} {args.mode} found near its "
                             "points")
        refined.append((name, axis, value, r))
    kappa, cost = estimate_kappa1([r for *_, r in refined], geom)
    print(f"kappa1 = {kappa:.6g} 1/mm^2 (straightness RMS {cost:.4f} px over {len(refined)} "
          "lines)", file=_messages(args))
    xl = [(v, r) for _, a, v, r in refined if a == "x"]
    yl = [(v, r) for _, a, v, r in refined if a == "y"]
    if len(xl) < 2 or len(yl) < 2 or len(xl) * len(yl) < 6:
        raise InputError("the coplanar Tsai fit needs at least 2 'x' and 2 'y' lines "
                         "(6+ intersections)")
    corners = intersect_grid([r for _, r in xl], [r for _, r in yl], kappa, geom).reshape(-1, 2)
    world = np.array([(vx, vy) for vx, _ in xl for vy, _ in yl]) * 1000.0  # metres -> mm
    ok = np.all(np.isfinite(corners), axis=1)
    fit = fit_coplanar_tsai(corners[ok], world[ok], geom, kappa1=kappa, fit_center=args.fit_center)
    c = fit.camera
    print(f"coplanar Tsai fit: RMS {fit.rms:.4f} px over {int(ok.sum())} intersections; "
          f"f={c.focal:.5g} mm kappa1={c.kappa1:.6g} Cx={c.cx:.2f} Cy={c.cy:.2f}",
          file=_messages(args))
    if _suffix(args.output, ".toml") == ".xml":
        write_tsai_xml(c, args.output, name=args.image.stem)
    else:
        write_tsai_toml(c, args.output)
    print(f"wrote {args.output}", file=_messages(args))
    return 0


def cmd_ground(args: argparse.Namespace) -> int:
    import numpy as np

    from ..calibrate.ground import fit_homography, fit_pose, read_point_pairs, write_ground_toml
    from ..calibrate.tsai import MAX_IMAGE_SIDE

    _check_out(args.output, args.force)
    img, world = read_point_pairs(args.points)
    size = None
    if args.size:
        try:
            size = tuple(int(v) for v in args.size.lower().split("x"))
        except ValueError:
            size = ()
        if len(size) != 2:
            raise ConfigError(f"--size must look like 768x576, got {args.size!r}")
        if not all(1 <= v <= MAX_IMAGE_SIDE for v in size):
            raise ConfigError(f"--size must be between 1 and {MAX_IMAGE_SIDE} pixels each way, "
                              f"got {args.size!r}")
    if args.intrinsics is not None:
        from ..calibrate.chessboard import read_opencv_yaml, write_opencv_yaml

        if _suffix(args.output, ".yml") not in (".yml", ".yaml"):
            raise ConfigError("with --intrinsics the output is an OpenCV camera .yml")
        cam = fit_pose(read_opencv_yaml(args.intrinsics), img, np.hstack([world, np.zeros((len(world), 1))]))
        px = cam.world_to_image(world)
        rms = float(np.sqrt(np.mean(np.sum((px - img) ** 2, axis=1))))
        write_opencv_yaml(args.output, cam)
        print(f"ground pose from {len(img)} pairs: RMS reprojection {rms:.3f} px",
              file=_messages(args))
    else:
        if _suffix(args.output, ".toml") != ".toml":
            raise ConfigError("the ground homography is written as .toml")
        g = fit_homography(img, world, size=size)
        write_ground_toml(g, args.output)
        print(f"ground homography from {len(img)} pairs: RMS {g.rms:.4f} m", file=_messages(args))
    print(f"wrote {args.output}", file=_messages(args))
    return 0
