"""Constant-velocity Kalman filter for boxes, as pure batched functions.

State ``x = [cx, cy, w, h, vx, vy, vw, vh]`` (centre, size and their velocities, pixels and
pixels/frame); measurement ``z = [cx, cy, w, h]``. Noise is proportional to the box height so the
same parameters work for near and far objects (the scheme of DeepSORT, Wojke et al. 2017).
All functions accept a batch: ``x`` (N, 8), ``P`` (N, 8, 8); N may be 0.
"""

from __future__ import annotations

import numpy as np

NDIM = 4
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
    """New tracks at rest from (N, 4) boxes → ``x`` (N, 8), ``P`` (N, 8, 8)."""
    z = box_to_z(boxes)
    n = len(z)
    x = np.zeros((n, 2 * NDIM))
    x[:, :NDIM] = z
    h = z[:, 3:4]
    std = np.hstack([2 * pos_std * h, 2 * pos_std * h, 2 * pos_std * h, 2 * pos_std * h,
                     10 * vel_std * h, 10 * vel_std * h, 10 * vel_std * h, 10 * vel_std * h])
    P = np.zeros((n, 2 * NDIM, 2 * NDIM))
    idx = np.arange(2 * NDIM)
    P[:, idx, idx] = std ** 2
    return x, P


_DIAG = np.arange(2 * NDIM)
_MEAS = np.arange(NDIM)


def process_noise(x: np.ndarray, pos_std: float, vel_std: float) -> np.ndarray:
    """Diagonal of the process noise ``Q``, (N, 8), scaled by each box height."""
    h2 = np.maximum(x[:, 3:4], 1.0) ** 2
    return h2 * _QW(pos_std, vel_std)


def _QW(pos_std: float, vel_std: float) -> np.ndarray:
    return np.array([pos_std ** 2] * NDIM + [vel_std ** 2] * NDIM)


def transition(dt: float = 1.0) -> np.ndarray:
    """The constant-velocity transition matrix for a step of ``dt`` frames."""
    if dt == 1.0:
        return F
    Fd = np.eye(2 * NDIM)
    Fd[:NDIM, NDIM:] = dt * np.eye(NDIM)
    return Fd


def predict(x: np.ndarray, P: np.ndarray, Q: np.ndarray, dt: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Kalman prediction ``x' = F x``, ``P' = F P Fᵀ + Q`` for a batch, over ``dt`` frames.

    ``Q`` is (N, 8, 8), or (N, 8) for a diagonal process noise (cheaper); it is the noise of the
    whole step (scale it by ``dt`` for longer steps)."""
    Fd = transition(dt)
    x2 = x @ Fd.T
    P2 = Fd @ P @ Fd.T
    if Q.ndim == 2:
        P2[:, _DIAG, _DIAG] += Q
    else:
        P2 += Q
    return x2, P2


def update(x: np.ndarray, P: np.ndarray, z: np.ndarray, meas_std: float) -> tuple[np.ndarray, np.ndarray]:
    """Kalman correction with measurements ``z`` (N, 4) for a batch of N tracks."""
    if len(x) == 0:
        return x.copy(), P.copy()
    # H = [I 0] selects the first NDIM states, so P Hᵀ, H P Hᵀ and H P are slices of P
    h = np.maximum(x[:, 3], 1.0)
    S = P[:, :NDIM, :NDIM].copy()
    S[:, _MEAS, _MEAS] += ((meas_std * h) ** 2)[:, None]   # + R (diagonal)
    PHt = P[:, :, :NDIM]                                      # (N, 8, 4)
    K = np.linalg.solve(S, PHt.transpose(0, 2, 1)).transpose(0, 2, 1)  # P Hᵀ S⁻¹
    innov = z - x[:, :NDIM]
    x2 = x + (K @ innov[:, :, None])[:, :, 0]
    P2 = P - K @ P[:, :NDIM, :]
    return x2, P2
