"""The images of the intermediate movies (``--save background,difference,motion,annotated``).

The thesis' movie scripts show the stages of the motion detector side by side; each stream is
written as its own video by :class:`~motiontrack.run.writers.IntermediateWriter`:

* ``background`` — the detector's current background estimate
  (:meth:`~motiontrack.motion.base.MotionDetector.background`; detectors without one, such as frame
  differencing, give a black frame), at processing scale;
* ``difference`` — the raw foreground mask before clean-up (the thresholded difference image), at
  processing scale;
* ``motion`` — the cleaned motion mask (``FrameResult.mask``) the regions are found in;
* ``annotated`` — the annotated frame (tracks and regions drawn), at full size.
"""

from __future__ import annotations

from typing import Iterable, Mapping

import numpy as np

from ..errors import ConfigError
from ..types import FrameResult
from .annotate import annotate_frame, frame_caption

__all__ = ["STREAMS", "parse_streams", "stream_image"]

#: stream name → file stem
STREAMS = ("background", "difference", "motion", "annotated")


def parse_streams(text: str | Iterable[str]) -> tuple[str, ...]:
    """``"background,difference"`` (or a list) → validated tuple of stream names, in given order."""
    items = [s.strip() for s in (text.split(",") if isinstance(text, str) else text)]
    items = [s for s in items if s]
    bad = [s for s in items if s not in STREAMS]
    if bad:
        raise ConfigError(f"unknown --save stream(s) {', '.join(bad)}; valid: {', '.join(STREAMS)}")
    return tuple(dict.fromkeys(items))


def stream_image(name: str, result: FrameResult, background: np.ndarray | None = None,
                 trail: int = 32, colors: Mapping[int, tuple[int, int, int]] | None = None
                 ) -> np.ndarray | None:
    """The image of stream ``name`` for one frame result (None when the frame has none, e.g. with
    external detections there is no mask); ``background`` is the motion detector's background
    image after this frame, when it has one; ``colors`` the track colours of the ``annotated``
    stream (:meth:`~motiontrack.render.colors.TrackColors.assign`).

    Returns
    -------
    ndarray (h, w) or (h, w, 3) uint8, or None
    """
    if name == "background":
        if background is None:
            mask = result.mask
            if mask is None:
                return None
            return np.zeros(mask.shape[:2], np.uint8)
        return np.asarray(background, dtype=np.uint8)
    if name == "difference":
        raw = result.raw_mask
        return None if raw is None else np.asarray(raw, dtype=np.uint8)
    if name == "motion":
        return None if result.mask is None else np.asarray(result.mask, dtype=np.uint8)
    if name == "annotated":
        return annotate_frame(result.frame, result.tracks, result.regions, result.mask, trail,
                              "none", text=frame_caption(result.index), colors=colors)
    raise ConfigError(f"unknown stream {name!r}; valid: {', '.join(STREAMS)}")
