"""Tracker per-frame cost (prediction + association + update) for 20 objects; target < 1 ms.

Twenty synthetic objects move at constant velocity with measurement noise, two of them crossing;
the same detections go through (a) our MultiObjectTracker and (b) a baseline doing the same
maths with one-track-at-a-time numpy Kalman filters (the textbook implementation), in one process.

Run: .venv/bin/python benchmarks/tracker.py
"""

from __future__ import annotations

import time

import numpy as np
from scipy.optimize import linear_sum_assignment

from motiontrack.config import TrackerConfig
from motiontrack.tracking.association import iou_matrix
from motiontrack.tracking.tracker import MultiObjectTracker


def scene(n_obj: int = 20, n_frames: int = 500, seed: int = 0) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    pos = rng.uniform(50, 600, (n_obj, 2))
    vel = rng.uniform(-3, 3, (n_obj, 2))
    size = rng.uniform(20, 40, (n_obj, 1)) * np.array([[1.0, 2.5]])
    frames = []
    for t in range(n_frames):
        p = pos + vel * t
        p = (p % 700) + rng.normal(0, 1.0, p.shape)
        frames.append(np.hstack([p, size]))
    return frames


class BaselineTrack:
    """One Kalman filter per object with per-object numpy (no batching)."""

    F = np.eye(8)
    F[:4, 4:] = np.eye(4)
    H = np.eye(4, 8)

    def __init__(self, box):
        self.x = np.r_[box[:2] + box[2:] / 2, box[2:], np.zeros(4)]
        self.P = np.eye(8) * 10.0

    def predict(self):
        self.x = self.F @ self.x
        self.P = self.F @ self.P @ self.F.T + np.eye(8)
        c = self.x[:4]
        return np.r_[c[:2] - c[2:] / 2, c[2:]]

    def update(self, box):
        z = np.r_[box[:2] + box[2:] / 2, box[2:]]
        S = self.H @ self.P @ self.H.T + np.eye(4) * 4.0
        K = self.P @ self.H.T @ np.linalg.inv(S)
        self.x = self.x + K @ (z - self.H @ self.x)
        self.P = (np.eye(8) - K @ self.H) @ self.P


def run_baseline(frames) -> float:
    tracks: list[BaselineTrack] = []
    t0 = time.perf_counter()
    for det in frames:
        pred = np.array([t.predict() for t in tracks]).reshape(-1, 4)
        iou = iou_matrix(pred, det)
        r, c = linear_sum_assignment(-iou) if iou.size else (np.zeros(0, int), np.zeros(0, int))
        used = set()
        for i, j in zip(r, c):
            if iou[i, j] > 0.1:
                tracks[i].update(det[j])
                used.add(j)
        for j in range(len(det)):
            if j not in used:
                tracks.append(BaselineTrack(det[j]))
    return (time.perf_counter() - t0) / len(frames)


def run_ours(frames) -> float:
    trk = MultiObjectTracker(TrackerConfig(), image_size=(700, 700))
    t0 = time.perf_counter()
    for det in frames:
        trk.update(det)
    return (time.perf_counter() - t0) / len(frames)


def main() -> None:
    frames = scene()
    run_ours(frames[:50])  # warm-up
    ours = min(run_ours(frames) for _ in range(3))
    base = min(run_baseline(frames) for _ in range(3))
    print(f"20 objects, {len(frames)} frames: ours {ours * 1e3:.3f} ms/frame, per-object baseline "
          f"{base * 1e3:.3f} ms/frame, ratio {base / ours:.2f}x; target < 1 ms: "
          f"{'met' if ours < 1e-3 else 'MISSED'}")


if __name__ == "__main__":
    main()
