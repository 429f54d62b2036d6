"""Constant-velocity Kalman filter for boxes, as pure batched functions.

State ``x = [cx, cy, w, h, vx, vy, vw, vh]`` (centre, size and their velocities, pixels and
pixels/frame); measurement ``z = [cx, cy, w, h]``. Noise is proportional to the box height so the
same parameters work for near and far objects (the scheme of DeepSORT, Wojke et al. 2017).

**Covariance in 2×2 blocks.** The transition couples each coordinate only with its own velocity,
the measurement selects the coordinates, and the process and measurement noises are diagonal, so
a covariance that starts diagonal stays made of four independent 2×2 blocks
``[[var(c), cov(c, v)], [cov(c, v), var(v)]]``, one per coordinate ``c`` of ``cx, cy, w, h``
(every other entry of the 8×8 matrix is exactly 0). The functions here keep only those blocks,
``P`` (N, 3, 4): ``P[:, 0]`` the coordinate variances, ``P[:, 1]`` the coordinate-velocity
covariances, ``P[:, 2]`` the velocity variances. Prediction and correction are then a few
element-wise operations instead of 8×8 matrix products and a 4×4 solve per track, with the same
result as the textbook formulas on the full matrix (:func:`full_covariance`; tested to 1e-9).

All functions accept a batch: ``x`` (N, 8), ``P`` (N, 3, 4); N may be 0.
"""

from __future__ import annotations

import numpy as np

NDIM = 4
# the model's transition and measurement matrices, for reference (the functions below work on
# the 2x2 blocks and never multiply by them)
F = np.eye(2 * NDIM)
F[:NDIM, NDIM:] = np.eye(NDIM)  # x_{t+1} = x_t + v_t (dt = 1 frame)
H = np.eye(NDIM, 2 * NDIM)


def box_to_z(boxes: np.ndarray) -> np.ndarray:
    """(N, 4) ``x, y, w, h`` → (N, 4) measurements ``cx, cy, w, h``."""
    b = np.asarray(boxes, np.float64).reshape(-1, 4)
    z = b.copy()
    z[:, :2] += b[:, 2:] / 2
    return z


def z_to_box(z: np.ndarray) -> np.ndarray:
    """(N, ≥4) states or measurements → (N, 4) ``x, y, w, h`` boxes."""
    z = np.asarray(z, np.float64).reshape(len(z), -1)
    b = z[:, :4].copy()
    b[:, :2] -= z[:, 2:4] / 2
    return b


def initiate(boxes: np.ndarray, pos_std: float, vel_std: float) -> tuple[np.ndarray, np.ndarray]:
    """New tracks at rest from (N, 4) boxes → ``x`` (N, 8), ``P`` (N, 3, 4) (diagonal: no
    coordinate-velocity covariance yet)."""
    z = box_to_z(boxes)
    n = len(z)
    x = np.zeros((n, 2 * NDIM))
    x[:, :NDIM] = z
    h = z[:, 3:4]
    P = np.zeros((n, 3, NDIM))
    P[:, 0] = (2 * pos_std * h) ** 2
    P[:, 2] = (10 * vel_std * h) ** 2
    return x, P


def process_noise(x: np.ndarray, pos_std: float, vel_std: float) -> np.ndarray:
    """Diagonal of the process noise ``Q`` per track, (N, 2, 4): the variances added to the
    coordinates and to the velocities in one frame, scaled by each box height."""
    h2 = (np.maximum(x[:, 3], 1.0) ** 2)[:, None, None]
    return h2 * np.array([[pos_std ** 2] * NDIM, [vel_std ** 2] * NDIM])


def predict(x: np.ndarray, P: np.ndarray, Q: np.ndarray, dt: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Kalman prediction ``x' = F x``, ``P' = F P Fᵀ + Q`` over ``dt`` frames for a batch.

    ``Q`` (N, 2, 4) is the noise of the whole step (see :func:`process_noise`; scale it by
    ``dt`` for longer steps)."""
    x2 = x.copy()
    x2[:, :NDIM] += dt * x[:, NDIM:]
    pxx, pxv, pvv = P[:, 0], P[:, 1], P[:, 2]
    P2 = np.empty_like(P)
    P2[:, 0] = pxx + (2.0 * dt) * pxv + (dt * dt) * pvv + Q[:, 0]
    P2[:, 1] = pxv + dt * pvv
    P2[:, 2] = pvv + Q[:, 1]
    return x2, P2


def update(x: np.ndarray, P: np.ndarray, z: np.ndarray, meas_std: float) -> tuple[np.ndarray, np.ndarray]:
    """Kalman correction with measurements ``z`` (N, 4) for a batch of N tracks; the
    measurement noise is ``meas_std`` times the predicted box height (per coordinate)."""
    pxx, pxv, pvv = P[:, 0], P[:, 1], P[:, 2]
    r = (meas_std * np.maximum(x[:, 3:4], 1.0)) ** 2
    s = pxx + r                       # innovation variance per coordinate
    k_pos, k_vel = pxx / s, pxv / s   # the two gains of each block
    innov = z - x[:, :NDIM]
    x2 = np.empty_like(x)
    x2[:, :NDIM] = x[:, :NDIM] + k_pos * innov
    x2[:, NDIM:] = x[:, NDIM:] + k_vel * innov
    P2 = np.empty_like(P)
    P2[:, 0] = pxx - k_pos * pxx
    P2[:, 1] = pxv - k_pos * pxv
    P2[:, 2] = pvv - k_vel * pxv
    return x2, P2


def full_covariance(P: np.ndarray) -> np.ndarray:
    """The 2×2 blocks ``P`` (N, 3, 4) as the full covariance matrices (N, 8, 8)."""
    n = len(P)
    full = np.zeros((n, 2 * NDIM, 2 * NDIM))
    i = np.arange(NDIM)
    full[:, i, i] = P[:, 0]
    full[:, i, i + NDIM] = P[:, 1]
    full[:, i + NDIM, i] = P[:, 1]
    full[:, i + NDIM, i + NDIM] = P[:, 2]
    return full
