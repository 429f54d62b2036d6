"""Dense optical flow (Farnebäck) as a picture: hue = direction, value = magnitude.

The flow itself and the flow-magnitude motion mask come from the ``farneback`` motion detector
(:class:`~motiontrack.motion.detectors.FarnebackMotion`, Farnebäck, "Two-frame motion estimation
based on polynomial expansion", SCIA 2003); this module only turns its ``last_flow`` into the usual
HSV visualisation (as in the OpenCV optical-flow tutorial) and writes videos of it.

Colour convention: direction is the angle of ``(dx, dy)`` in *image* coordinates (x right, y down),
``θ = atan2(dy, dx)`` in [0°, 360°), so 0° = moving right, 90° = moving down, 180° = left,
270° = up; OpenCV hue is ``θ / 2`` (0..179): right = red (0), down = yellow-green (45),
left = cyan (90), up = blue-violet (135). Saturation is 255; value is ``255 · min(1, |flow| / m)``
with ``m`` = ``max_magnitude`` (px/frame) or, when it is ``None``, the frame's largest magnitude.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import cv2
import numpy as np

from ..config import FarnebackParams
from ..errors import ConfigError

log = logging.getLogger(__name__)

__all__ = ["flow_to_hsv", "flow_to_bgr", "hue_to_angle", "DenseFlow", "FlowVideoStats",
           "write_flow_videos"]


def flow_to_hsv(flow: np.ndarray, max_magnitude: float | None = None) -> np.ndarray:
    """HSV image of a flow field.

    Parameters
    ----------
    flow : (H, W, 2) float, ``(dx, dy)`` in pixels per frame.
    max_magnitude : magnitude (px/frame) shown at full brightness; ``None`` = this field's maximum.

    Returns
    -------
    (H, W, 3) uint8 OpenCV HSV: hue = direction / 2 (0..179), saturation 255, value ∝ magnitude.
    """
    flow = np.asarray(flow, np.float32)
    if flow.ndim != 3 or flow.shape[2] != 2:
        raise ConfigError(f"flow must have shape (H, W, 2), got {flow.shape}")
    if max_magnitude is not None and not max_magnitude > 0:
        raise ConfigError(f"max_magnitude must be > 0, got {max_magnitude}")
    hsv = np.zeros(flow.shape[:2] + (3,), np.uint8)
    if flow.size == 0:
        return hsv
    mag, ang = cv2.cartToPolar(flow[..., 0], flow[..., 1], angleInDegrees=True)
    top = float(max_magnitude) if max_magnitude is not None else float(mag.max())
    hsv[..., 0] = np.round(ang / 2.0).astype(np.int32) % 180
    hsv[..., 1] = 255
    if top > 0:
        hsv[..., 2] = np.round(np.clip(mag / top, 0.0, 1.0) * 255.0).astype(np.uint8)
    return hsv


def flow_to_bgr(flow: np.ndarray, max_magnitude: float | None = None) -> np.ndarray:
    """BGR picture of a flow field (see :func:`flow_to_hsv`), (H, W, 3) uint8."""
    return cv2.cvtColor(flow_to_hsv(flow, max_magnitude), cv2.COLOR_HSV2BGR)


def hue_to_angle(hue: np.ndarray | float) -> np.ndarray:
    """OpenCV hue (0..179) back to the flow direction in degrees [0, 360)."""
    return (np.asarray(hue, np.float64) * 2.0) % 360.0


class DenseFlow:
    """Farnebäck flow per frame, via the ``farneback`` motion detector (no duplicated maths).

    ``apply(image)`` returns ``(flow (H, W, 2) float32 px/frame, mask (H, W) uint8 0/255)``; the
    first frame gives zero flow and an empty mask.
    """

    def __init__(self, params: FarnebackParams | None = None) -> None:
        from dataclasses import asdict

        from . import DETECTORS

        self.params = params or FarnebackParams()
        self.detector = DETECTORS.create("farneback", **asdict(self.params))

    def apply(self, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        mask = self.detector.apply(image)
        return self.detector.last_flow, mask


@dataclass(frozen=True)
class FlowVideoStats:
    """What :func:`write_flow_videos` measured: frames written and flow magnitude statistics
    (px/frame, over all pixels of all frames after the first); ``stopped`` when ``should_stop``
    ended the run early."""

    frames: int
    mean_magnitude: float
    max_magnitude: float
    moving_fraction: float
    stopped: bool = False


def write_flow_videos(frames: Any, flow_path: str | Path, fps: float, *,
                      mask_path: str | Path | None = None, codec: str = "vp80",
                      params: FarnebackParams | None = None, max_magnitude: float | None = None,
                      progress: Callable[[int], None] | None = None,
                      should_stop: Callable[[], bool] | None = None) -> FlowVideoStats:
    """Write the HSV flow video (and optionally the flow-magnitude mask video) of ``frames``.

    Parameters
    ----------
    frames : iterable of (H, W, 3) uint8 BGR images or :class:`~motiontrack.types.Frame`.
    flow_path, mask_path : output video files (written atomically by ``VideoSink``).
    fps : frame rate of the output videos.
    params : Farnebäck parameters (``threshold`` sets the mask).
    max_magnitude : fixed brightness scale (px/frame) so colours are comparable across frames;
        ``None`` scales each frame to its own maximum.
    progress : called with 1 after each frame.
    should_stop : polled after each frame; when it returns True the videos are closed with the
        frames so far and the result has ``stopped=True``.
    """
    from ..io.video import VideoSink

    flow_est = DenseFlow(params)
    n = 0
    total = 0.0
    count = 0
    moving = 0
    peak = 0.0
    stopped = False
    flow_sink = VideoSink(flow_path, fps, codec)
    mask_sink = VideoSink(mask_path, fps, codec) if mask_path is not None else None
    try:
        for item in frames:
            img = getattr(item, "image", item)
            flow, mask = flow_est.apply(img)
            flow_sink.write(flow_to_bgr(flow, max_magnitude))
            if mask_sink is not None:
                mask_sink.write(mask)
            if n > 0:
                mag = cv2.magnitude(flow[..., 0], flow[..., 1])
                total += float(mag.sum())
                count += mag.size
                peak = max(peak, float(mag.max()))
                moving += int(np.count_nonzero(mask))
            n += 1
            if progress is not None:
                progress(1)
            if should_stop is not None and should_stop():
                stopped = True
                break
    finally:
        flow_sink.close()
        if mask_sink is not None:
            mask_sink.close()
    return FlowVideoStats(frames=n, mean_magnitude=total / count if count else 0.0,
                          max_magnitude=peak, moving_fraction=moving / count if count else 0.0,
                          stopped=stopped)
