"""Scene analytics: lines, zones, dwell, loitering, stationary tracks and speed as events.

* :mod:`.scene` — the scene file (TOML) → a validated :class:`Scene` in source pixels;
* :mod:`.geometry` — signed side of a line, segment meeting, point in polygon;
* :mod:`.lines`, :mod:`.zones`, :mod:`.movement` — the rules, over arrays of tracks;
* :mod:`.engine` — :class:`Analytics`: a frame's tracks in, its events and counts out.

See ``docs/analytics.md``.
"""

from .engine import Analytics
from .scene import Scene, load_scene, parse_scene

__all__ = ["Analytics", "Scene", "load_scene", "parse_scene"]
