"""motiontrack: find and follow moving objects and people in video, and measure how well it went.

Python API::

    import motiontrack
    for result in motiontrack.track("video.mp4"):
        print(result.index, [(t.id, t.box) for t in result.tracks])
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .types import Annotations, Box, Frame, FrameResult, Region, Track, TrackState

__version__ = "0.1.0"

__all__ = [
    "Annotations", "Box", "Frame", "FrameResult", "Region", "Track", "TrackState", "track",
    "__version__",
]

if TYPE_CHECKING:  # pragma: no cover
    from .config import PipelineConfig
    from .pipeline import TrackRun


def track(source: Any, config: "PipelineConfig | str | None" = None, **kwargs: Any) -> "TrackRun":
    """Run the pipeline on ``source``: an iterator of one :class:`FrameResult` per frame.

    ``source`` is anything :func:`motiontrack.io.sources.open_source` accepts (a path, a camera
    index, a URL, an image folder or glob, ``"synth:NAME"``, or a ``Source`` object). ``config``
    is a :class:`~motiontrack.config.PipelineConfig`, a TOML path, or None for the defaults.

    The iterator (:class:`~motiontrack.pipeline.TrackRun`) owns the source and the pipeline's
    threads: use it in a ``with`` block or call ``close()`` to stop early; one left open is
    closed when it is garbage-collected or when the interpreter exits::

        with motiontrack.track("video.mp4") as frames:
            first = next(frames)
    """
    from .pipeline import run

    return run(source, config, **kwargs)
