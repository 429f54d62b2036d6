"""The frames of a video file a test wrote, decoded by OpenCV."""

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
