"""Dense optical flow (Farnebäck) per frame, through the ``farneback`` motion detector.

The flow itself and the flow-magnitude motion mask come from
:class:`~motiontrack.motion.detectors.FarnebackMotion` (Farnebäck, "Two-frame motion estimation
based on polynomial expansion", SCIA 2003); :mod:`motiontrack.render.flow` draws the flow as a
colour picture.
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from ..config import FarnebackParams
from .base import DETECTORS

__all__ = ["DenseFlow"]


class DenseFlow:
    """Farnebäck flow per frame, via the ``farneback`` motion detector (no duplicated maths).

    ``apply(image)`` returns ``(flow (H, W, 2) float32 px/frame, mask (H, W) uint8 0/255)``; the
    first frame gives zero flow and an empty mask.
    """

    def __init__(self, params: FarnebackParams | None = None) -> None:
        self.params = params or FarnebackParams()
        self.detector = DETECTORS.create("farneback", **asdict(self.params))

    def apply(self, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        mask = self.detector.apply(image)
        return self.detector.last_flow, mask
