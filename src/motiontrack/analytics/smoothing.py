"""Tracks' positions smoothed for the rules that measure them (``speed``, ``stationary``).

A box's anchor jitters from frame to frame: legs open and close, a neighbour joins the blob for
a frame, the motion mask loses a shoulder. Speeds from raw anchors add that jitter up (a walker
at 1.4 m/s read 3.7 m/s over a second on PETS 2009), and a standing person's raw anchor wanders
out of a stationary radius now and then. The rules measure a smoothed trajectory instead, with
its uncertainty.

Each track's anchor is followed by a constant-velocity Kalman filter (one row per track of the
engine's rows, batched over the tracks of a frame; :class:`Smoother`):

* **measurement noise**: the anchor's standard deviation is :data:`NOISE` of the box's height in
  each image axis;
* **process noise**: a white acceleration of :data:`ACCEL` box heights per second squared in each
  axis (a walker changing pace or turning);
* **start**: the first position as measured, its speed unknown (:data:`SPEED0` box heights per
  second in each axis: a prior that says nothing), so the second position sets the speed with the
  uncertainty of two measurements a frame apart, whatever the object's pace;
* **outliers**: a measurement farther than :data:`GATE` (chi-squared, 2 degrees of freedom,
  99.9 %) from its prediction is skipped (a box that jumped as two people merged); after
  :data:`JUMP` such measurements in a row the filter starts again at the last one, its speed
  unknown (the id went over to another object).

In metres, the same noises are carried onto the ground plane through the camera's local
Jacobian at the foot point (``J``, metres per pixel in each image axis): a pixel of jitter far
from the camera is metres, near it centimetres, and the filter on the ground weighs each
measurement by what it is worth. The filter works in seconds: frames are divided by the rate.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["Smoother", "Smoothed", "NOISE", "ACCEL", "SPEED0", "GATE", "JUMP", "jacobians"]

#: standard deviation of an anchor's jitter in each image axis, as a fraction of the box height
NOISE = 0.05
#: standard deviation of the acceleration, box heights per second squared in each image axis
ACCEL = 0.5
#: standard deviation of a new track's speed, box heights per second in each image axis: far
#: above any object's pace, so the first two measurements set the speed
SPEED0 = 50.0
#: squared Mahalanobis distance beyond which a measurement is an outlier (chi-squared, 2 dof,
#: 99.9 %)
GATE = 13.8
#: outliers in a row after which the filter starts again at the measurement
JUMP = 3


@dataclass(frozen=True)
class Smoothed:
    """One frame's smoothed tracks (rows in the order of the frame's tracks).

    Attributes
    ----------
    position : (N, 2) float64
        Smoothed anchors (pixels or metres); NaN for a track never measured in this unit.
    velocity : (N, 2) float64
        Per second.
    position_cov, velocity_cov : (N, 2, 2) float64
        Their covariances.
    updates : (N,) int64
        Measurements since the filter (re)started: 0 for a track never measured.
    """

    position: np.ndarray
    velocity: np.ndarray
    position_cov: np.ndarray
    velocity_cov: np.ndarray
    updates: np.ndarray

    def speed(self) -> tuple[np.ndarray, np.ndarray]:
        """(N,) speeds and their standard deviations along the direction of motion."""
        v = self.velocity
        speed = np.hypot(v[:, 0], v[:, 1])
        u = v / np.where(speed > 0, speed, 1.0)[:, None]
        var = np.einsum("ni,nij,nj->n", u, self.velocity_cov, u)
        # at rest every direction is the direction of motion: take the larger axis
        rest = speed <= 0
        if rest.any():
            var[rest] = np.linalg.eigvalsh(self.velocity_cov[rest])[:, -1]
        return speed, np.sqrt(np.maximum(var, 0.0))


def jacobians(world_of: Callable[[np.ndarray], np.ndarray], boxes: np.ndarray,
              base: np.ndarray | None = None) -> np.ndarray:
    """(N, 2, 2) metres per pixel of the ground position of each box's foot point, in each image
    axis (columns: a pixel right, a pixel down), by finite differences; NaN above the horizon.
    ``base``: ``world_of(boxes)`` when the caller has it already."""
    b = np.asarray(boxes, np.float64).reshape(-1, 4)
    base = world_of(b) if base is None else base
    right, down = b.copy(), b.copy()
    right[:, 0] += 1.0
    down[:, 1] += 1.0
    return np.stack([world_of(right) - base, world_of(down) - base], axis=2)


class Smoother:
    """Constant-velocity Kalman filters of the tracks' anchors, one per engine row (see the
    module notes).

    Parameters
    ----------
    fps : float
        Frames per second.
    """

    def __init__(self, fps: float) -> None:
        self.fps = float(fps)
        self.x = np.zeros((16, 4))
        self.P = np.zeros((16, 4, 4))
        self.frame = np.zeros(16, np.int64)
        self.updates = np.zeros(16, np.int64)
        self.outliers = np.zeros(16, np.int64)

    def _room(self, rows: np.ndarray) -> None:
        need = int(rows.max()) + 1 if len(rows) else 0
        n = len(self.x)
        if need <= n:
            return
        while n < need:
            n *= 2
        for name in ("x", "P", "frame", "updates", "outliers"):
            old = getattr(self, name)
            new = np.zeros((n,) + old.shape[1:], old.dtype)
            new[:len(old)] = old
            setattr(self, name, new)

    def clear(self, rows: np.ndarray) -> None:
        """Rows taken by new tracks start afresh."""
        if len(rows):
            self._room(rows)
            self.updates[rows] = 0
            self.outliers[rows] = 0

    def step(self, frame: int, rows: np.ndarray, z: np.ndarray, heights: np.ndarray,
             jac: np.ndarray | None = None) -> Smoothed:
        """The filters of ``rows`` after the measurements ``z`` (N, 2) of frame ``frame``, of
        boxes ``heights`` (N,) pixels tall; ``jac`` (N, 2, 2): metres per pixel at each foot
        point when ``z`` is on the ground (None: ``z`` in pixels). A row with a non-finite
        measurement or Jacobian is only predicted."""
        rows = np.asarray(rows, np.int64)
        self._room(rows)
        n = len(rows)
        z = np.asarray(z, np.float64).reshape(-1, 2)
        h = np.maximum(np.asarray(heights, np.float64).reshape(-1), 1.0)
        # each axis's noises in pixels, carried to the measurement's unit by J (J = I in pixels)
        J = np.broadcast_to(np.eye(2), (n, 2, 2)) if jac is None else np.asarray(jac, np.float64)
        ok = np.isfinite(z).all(axis=1) & np.isfinite(J).all(axis=(1, 2))
        JJt = np.einsum("nij,nkj->nik", np.where(ok[:, None, None], J, 0.0),
                        np.where(ok[:, None, None], J, 0.0))
        R = JJt * ((NOISE * h) ** 2)[:, None, None]
        A = JJt * ((ACCEL * h) ** 2)[:, None, None]
        old = self.updates[rows] > 0
        self._start(rows[ok & ~old], z[ok & ~old], R[ok & ~old])
        known = old
        if known.any():
            r = rows[known]
            dt = np.maximum(frame - self.frame[r], 0) / self.fps
            self._predict(r, dt, A[known])
            meas = known & ok
            if meas.any():
                self._update(rows[meas], z[meas], R[meas])
        self.frame[rows[ok | old]] = frame
        return self._read(rows)

    def _start(self, rows: np.ndarray, z: np.ndarray, R: np.ndarray) -> None:
        """Rows start at ``z`` (measurement covariance ``R``), the speed unknown: 0 with a
        standard deviation of :data:`SPEED0` heights a second (``R`` scaled from :data:`NOISE`
        heights)."""
        if not len(rows):
            return
        self.x[rows, :2] = z
        self.x[rows, 2:] = 0.0
        P = np.zeros((len(rows), 4, 4))
        P[:, :2, :2] = R
        P[:, 2:, 2:] = R * (SPEED0 / NOISE) ** 2
        self.P[rows] = P
        self.updates[rows] = 1
        self.outliers[rows] = 0

    def _predict(self, rows: np.ndarray, dt: np.ndarray, A: np.ndarray) -> None:
        """Each row ``dt`` seconds on (white acceleration of covariance ``A`` per s²)."""
        x, P = self.x[rows], self.P[rows]
        x[:, :2] += dt[:, None] * x[:, 2:]
        d = dt[:, None, None]
        # F P F^T with F = [[I, dt I], [0, I]], in 2x2 blocks
        pp, pv, vv = P[:, :2, :2], P[:, :2, 2:], P[:, 2:, 2:]
        new = np.empty_like(P)
        new[:, :2, :2] = pp + d * (pv + pv.transpose(0, 2, 1)) + d * d * vv + A * d ** 3 / 3
        new[:, :2, 2:] = pv + d * vv + A * d ** 2 / 2
        new[:, 2:, :2] = new[:, :2, 2:].transpose(0, 2, 1)
        new[:, 2:, 2:] = vv + A * d
        self.x[rows], self.P[rows] = x, new

    def _update(self, rows: np.ndarray, z: np.ndarray, R: np.ndarray) -> None:
        x, P = self.x[rows], self.P[rows]
        S = P[:, :2, :2] + R
        Sinv = np.linalg.inv(S)
        y = z - x[:, :2]
        d2 = np.einsum("ni,nij,nj->n", y, Sinv, y)
        inlier = d2 <= GATE
        self.outliers[rows] = np.where(inlier, 0, self.outliers[rows] + 1)
        K = np.einsum("nij,njk->nik", P[:, :, :2], Sinv)             # (n, 4, 2)
        upd = inlier
        x[upd] += np.einsum("nij,nj->ni", K[upd], y[upd])
        P[upd] -= np.einsum("nij,njk->nik", K[upd], P[upd][:, :2, :])
        P[upd] = (P[upd] + P[upd].transpose(0, 2, 1)) / 2
        self.x[rows], self.P[rows] = x, P
        self.updates[rows[upd]] += 1
        jump = self.outliers[rows] >= JUMP
        if jump.any():
            # restart at the measurement: the speed unknown again
            self._start(rows[jump], z[jump], R[jump])

    def _read(self, rows: np.ndarray) -> Smoothed:
        x, P = self.x[rows], self.P[rows]
        never = self.updates[rows] == 0
        pos = x[:, :2].copy()
        pos[never] = np.nan
        return Smoothed(pos, x[:, 2:].copy(), P[:, :2, :2].copy(), P[:, 2:, 2:].copy(),
                        self.updates[rows].copy())
