"""Scene analytics: lines, zones, dwell, loitering, stationary tracks and speed as events.

* :mod:`.scene` — the scene file (TOML) → a validated :class:`Scene` in source pixels;
* :mod:`.rule` — the :class:`~.rule.Rule` protocol and :data:`RULES`, the rules by name;
* :mod:`.rules` — the built-in rules, one module each: lines, zones, stationary, abandoned,
  speed;
* :mod:`.geometry` — signed side of a line, segment meeting, point in polygon;
* :mod:`.lines`, :mod:`.zones`, :mod:`.movement`, :mod:`.abandoned` — the array functions the
  rules call;
* :mod:`.engine` — :class:`Analytics`: a frame's tracks in, its events and counts out.

See ``docs/analytics.md``.
"""

from .engine import Analytics
from .rule import RULES, Rule
from .scene import Scene, load_scene, parse_scene

__all__ = ["Analytics", "RULES", "Rule", "Scene", "load_scene", "parse_scene"]
