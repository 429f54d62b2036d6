"""Events to evaluate: an events file as it is, or a tracks file through a scene's analytics."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..analytics import load_scene
from ..errors import ConfigError
from ..io.annotations import read_annotations
from ..io.events import EventsFile, is_events_file, read_events
from ..types import events_header
from .analyze import analysed_events
from .folder import RunFolder

__all__ = ["load_events"]


def load_events(path: str | Path, scene: str | Path | None = None, fps: float | None = None,
                camera: Any = None, what: str = "events") -> EventsFile:
    """The events of ``path``: an events file is read; any other file is a tracks file (any
    supported annotation format) analysed with the scene file ``scene`` exactly as ``analyze``
    does (frame rate ``fps``, or the one stated beside the tracks).

    Raises
    ------
    ConfigError
        A tracks file without ``scene``, or without a frame rate.
    InputError
        A malformed events, tracks or scene file.
    """
    path = Path(path)
    if is_events_file(path):
        return read_events(path)
    if scene is None:
        raise ConfigError(f"{what} {path} is not an events file (its first line is not the "
                          "motiontrack.events header); give --scene to analyse it as a tracks "
                          "file")
    rate = fps if fps is not None else RunFolder.beside(path).frame_rate()
    if rate is None:
        raise ConfigError(f"analysing {path.name} needs its frame rate: give --fps")
    spec = load_scene(scene, camera)
    tracks = read_annotations(path)
    # analyze's own source and processor, so the events are exactly those `analyze` writes
    events = analysed_events(tracks, spec, rate, camera=camera, source=str(path))
    return EventsFile(events_header(rate, str(path), spec.source), events)
