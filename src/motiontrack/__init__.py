"""motiontrack: find and follow moving objects and people in video, and measure how well it went.

Python API::

    import motiontrack
    for result in motiontrack.track("video.mp4"):
        print(result.index, [(t.id, t.box) for t in result.tracks])

    import motiontrack.batch
    rows = motiontrack.batch.run_batch(["videos/"], "results")   # one track run per video, on Dask

The package imports nothing above the layers it offers here: ``motiontrack.batch`` (Dask) is
a subpackage to import as any other.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .version import __version__

__all__ = [
    "Annotations", "Box", "Frame", "FrameResult", "Region", "Track", "TrackState", "track",
    "__version__",
]

#: the names of :mod:`motiontrack.types` offered here, imported on first use: importing the
#: package (every command does, ``--help`` included) then costs no NumPy
_TYPES = frozenset({"Annotations", "Box", "Frame", "FrameResult", "Region", "Track", "TrackState"})

if TYPE_CHECKING:  # pragma: no cover
    from .config import PipelineConfig
    from .pipeline import TrackRun
    from .types import Annotations, Box, Frame, FrameResult, Region, Track, TrackState


def __getattr__(name: str) -> Any:
    if name in _TYPES:
        from . import types

        value = getattr(types, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_TYPES})


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
