"""Video files of synthetic scenes a test writes, and their frames decoded by OpenCV."""

from __future__ import annotations

import cv2
import numpy as np


def read_frames(path) -> list[np.ndarray]:
    """Every frame of the video at ``path``, in order (BGR)."""
    cap = cv2.VideoCapture(str(path))
    frames = []
    try:
        while True:
            ok, img = cap.read()
            if not ok:
                return frames
            frames.append(img)
    finally:
        cap.release()


def write_synth_video(path, spec: str):
    """Write the frames of the synthetic scene ``spec`` (``"synth:walker?n_frames=12"``) to the
    MJPG video ``path`` at 10 fps; returns the scene's ground truth (Annotations)."""
    import motiontrack.synth  # noqa: F401 - registers synth:
    from motiontrack.io.sources import open_source

    with open_source(spec) as src:
        writer = None
        for f in src:
            if writer is None:
                h, w = f.image.shape[:2]
                writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10, (w, h))
            writer.write(f.image)
        writer.release()
        return src.ground_truth()
