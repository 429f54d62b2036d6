"""Intermediate image movies (``--save background,difference,motion``).

The thesis' movie scripts show the stages of the motion detector side by side. This module writes
each requested stream as its own video while the pipeline runs:

* ``background`` — the detector's current background estimate
  (:meth:`~motiontrack.motion.base.MotionDetector.background`; detectors without one, such as frame
  differencing, give a black frame), at processing scale;
* ``difference`` — the raw foreground mask before clean-up (``FrameResult.extras["raw_mask"]``:
  the thresholded difference image), at processing scale;
* ``motion`` — the cleaned motion mask (``FrameResult.mask``) the regions are found in;
* ``annotated`` — the annotated frame (tracks and regions drawn), at full size.

Usage (``TrackJob`` or any loop over :class:`~motiontrack.pipeline.Pipeline`)::

    writer = IntermediateWriter(out_dir, ("background", "difference", "motion"), fps, codec)
    try:
        for frame in source:
            res = pipe.process(frame)
            writer.write(res, pipe.detector)
    finally:
        writer.close()
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Iterable

import numpy as np

from .errors import ConfigError
from .io.video import VideoSink, extension_for
from .types import FrameResult

log = logging.getLogger(__name__)

__all__ = ["STREAMS", "parse_streams", "IntermediateWriter", "stream_image"]

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


def stream_image(name: str, result: FrameResult, detector: Any = None, trail: int = 32) -> np.ndarray | None:
    """The image of stream ``name`` for one frame result (None when the frame has none, e.g. with
    external detections there is no mask).

    Returns
    -------
    ndarray (h, w) or (h, w, 3) uint8, or None
    """
    if name == "background":
        bg = detector.background() if detector is not None else None
        if bg is None:
            mask = result.mask
            if mask is None:
                return None
            return np.zeros(mask.shape[:2], np.uint8)
        return np.asarray(bg, dtype=np.uint8)
    if name == "difference":
        raw = result.extras.get("raw_mask") if result.extras else None
        return None if raw is None else np.asarray(raw, dtype=np.uint8)
    if name == "motion":
        return None if result.mask is None else np.asarray(result.mask, dtype=np.uint8)
    if name == "annotated":
        from .annotate import annotate_frame

        return annotate_frame(result.frame, result.tracks, result.regions, result.mask, trail,
                              False, text=f"frame {result.index}")
    raise ConfigError(f"unknown stream {name!r}; valid: {', '.join(STREAMS)}")


class IntermediateWriter:
    """Write the requested streams of every frame to ``out_dir/<stream><ext>`` (atomically: each
    file appears when :meth:`close` is called).

    Parameters
    ----------
    out_dir : folder for the videos (created).
    streams : names from :data:`STREAMS`.
    fps : frames per second of the videos.
    codec : a :data:`motiontrack.io.video.CODECS` name (default VP8 WebM).
    """

    def __init__(self, out_dir: str | Path, streams: Iterable[str], fps: float = 25.0,
                 codec: str = "vp80") -> None:
        self.streams = parse_streams(list(streams))
        self.out_dir = Path(out_dir)
        self.paths = {s: self.out_dir / f"{s}{extension_for(codec)}" for s in self.streams}
        self.sinks = {s: VideoSink(p, fps, codec) for s, p in self.paths.items()}
        if self.streams:
            self.out_dir.mkdir(parents=True, exist_ok=True)

    def write(self, result: FrameResult, detector: Any = None) -> None:
        """Append one frame's images (``detector``: the pipeline's motion detector, for the
        background; ``pipe.detector``)."""
        for s, sink in self.sinks.items():
            img = stream_image(s, result, detector)
            if img is not None:
                sink.write(img)

    def close(self) -> dict[str, str]:
        """Finish every video; returns stream → path of those that received frames."""
        out = {}
        for s, sink in self.sinks.items():
            sink.close()
            if sink.frames:
                out[s] = str(self.paths[s])
        return out

    def __enter__(self) -> "IntermediateWriter":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
