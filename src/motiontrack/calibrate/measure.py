"""Measurements in metres from boxes and a calibrated camera: positions, speeds, heights.

Method
------
* **Position**: the foot point of a box is its bottom centre ``(x + w/2, y + h)``; it is back-projected
  onto the ground plane ``Z = 0`` (``camera.image_to_world``). This assumes the person stands on the
  ground and the box bottom touches the feet.
* **Path length**: per track, positions are ordered by frame; the path length is the sum of the
  distances between consecutive valid positions (box jitter included).
* **Speed**: :func:`motiontrack.speed.mean_speed`: the mean over the track's frames of the
  straight distance from its oldest position of the last ``window_s`` seconds to the current one
  over their time apart (frames / ``fps``). The scene rule ``[speed]`` measures the same window
  on the track's smoothed trajectory, with its uncertainty (an alarm, not a mean).
* **Height** (the "vertical through the foot point" construction, cf. Criminisi, Reid & Zisserman,
  "Single view metrology", IJCV 2000, for the single-view idea): the head is assumed to lie on the
  world vertical ``L(s) = F + s e_z`` through the foot point ``F``. The top-centre pixel of the box
  defines a viewing ray ``C + t d``. Because of noise the two lines rarely meet, so the height is the
  parameter ``s`` of the point on ``L`` closest to the ray (closest approach of two 3-D lines)::

      w0 = F - C,  s = (d_z (d · w0) - w0_z) / (1 - d_z²)

  This needs a camera with a full pose (``rays``): Tsai or a posed OpenCV camera. A ground-plane
  homography cannot measure heights, so heights are ``NaN`` / ``None`` there. The track's height is the
  median over its boxes (robust to partly occluded frames).
"""

from __future__ import annotations

import math

import numpy as np

from ..speed import SPEED_WINDOW_S, mean_speed

__all__ = ["foot_points", "world_positions", "box_heights", "track_measurements"]


def _boxes(boxes) -> np.ndarray:
    b = np.asarray(boxes, dtype=np.float64)
    return b.reshape(-1, 4) if b.size else np.zeros((0, 4))


def foot_points(boxes) -> np.ndarray:
    """(N, 4) ``x, y, w, h`` boxes → (N, 2) bottom-centre pixels."""
    b = _boxes(boxes)
    return np.stack([b[:, 0] + b[:, 2] / 2.0, b[:, 1] + b[:, 3]], axis=1)


def world_positions(boxes, camera) -> np.ndarray:
    """Ground-plane position (metres) of each box's bottom centre.

    Parameters
    ----------
    boxes : (N, 4) float, ``x, y, w, h`` pixels.
    camera : any camera from :func:`motiontrack.calibrate.camera.load_camera`.

    Returns
    -------
    (N, 2) float64 ``X, Y`` metres; NaN where the foot point is above the horizon.
    """
    b = _boxes(boxes)
    if len(b) == 0:
        return np.zeros((0, 2))
    return np.asarray(camera.image_to_world(foot_points(b)), dtype=np.float64)


def box_heights(boxes, camera) -> np.ndarray:
    """Estimated height (metres) of the object in each box, see the module docstring.

    Returns
    -------
    (N,) float64; all NaN when the camera has no ``rays`` (homography only).
    """
    b = _boxes(boxes)
    n = len(b)
    if n == 0:
        return np.zeros(0)
    if not hasattr(camera, "rays"):
        return np.full(n, np.nan)
    foot = world_positions(b, camera)
    F = np.hstack([foot, np.zeros((n, 1))])
    top = np.stack([b[:, 0] + b[:, 2] / 2.0, b[:, 1]], axis=1)
    C, d = camera.rays(top)
    w0 = F - C
    dz = d[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (dz * np.sum(d * w0, axis=1) - w0[:, 2]) / (1.0 - dz * dz)
    return np.where(np.isfinite(s), s, np.nan)


def _num(v: float) -> float | None:
    return None if v is None or not math.isfinite(v) else float(v)


def track_measurements(frames, ids, boxes, camera, fps: float,
                       window_s: float = SPEED_WINDOW_S) -> dict[int, dict]:
    """Per-track speed, path length and height.

    Parameters
    ----------
    frames : (N,) int
        Frame numbers (any origin; only differences matter).
    ids : (N,) int
        Track ids.
    boxes : (N, 4) float
        ``x, y, w, h`` pixels.
    camera : camera object (see :func:`world_positions`).
    fps : float
        Frames per second (> 0): the rate the frames were recorded at (``--fps``).
    window_s : float
        Seconds of the window of each speed (:func:`motiontrack.speed.mean_speed`).

    Returns
    -------
    dict
        ``{track_id: {"frames": n, "first_frame", "last_frame", "duration_s", "path_length_m",
        "mean_speed_mps", "speed_window_s", "speed_fps", "height_m"}}`` (``speed_window_s`` and
        ``speed_fps``: the window and frame rate of the speed); undefined values (a track shorter
        than half a window, no height model) are ``None`` so the result is valid JSON.
    """
    if not (fps > 0 and math.isfinite(fps)):
        raise ValueError(f"fps must be > 0, got {fps}")
    fr = np.asarray(frames, dtype=np.int64).reshape(-1)
    ti = np.asarray(ids, dtype=np.int64).reshape(-1)
    b = _boxes(boxes)
    if not (len(fr) == len(ti) == len(b)):
        raise ValueError(f"frames, ids, boxes must have equal length, got {len(fr)}, {len(ti)}, {len(b)}")
    if len(b) == 0:
        return {}
    pos = world_positions(b, camera)
    hts = box_heights(b, camera)
    out: dict[int, dict] = {}
    for tid in np.unique(ti):
        idx = np.flatnonzero(ti == tid)
        idx = idx[np.argsort(fr[idx], kind="stable")]
        f = fr[idx]
        p = pos[idx]
        ok = np.all(np.isfinite(p), axis=1)
        length = float(np.sum(np.linalg.norm(np.diff(p[ok], axis=0), axis=1)))
        duration = (f[-1] - f[0]) / fps
        speed = mean_speed(f[ok].tolist(), p[ok].tolist(), fps, window_s)
        h = hts[idx]
        h = h[np.isfinite(h)]
        out[int(tid)] = {
            "frames": int(len(idx)),
            "first_frame": int(f[0]),
            "last_frame": int(f[-1]),
            "duration_s": float(duration),
            "path_length_m": float(length),
            "mean_speed_mps": _num(speed),
            "speed_window_s": float(window_s),
            "speed_fps": float(fps),
            "height_m": _num(float(np.median(h))) if len(h) else None,
        }
    return out
