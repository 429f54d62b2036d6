"""The built-in analytics rules, registered in :data:`~motiontrack.analytics.rule.RULES` in
the order the scene file lists their tables and a frame's events list theirs: lines
(``line_cross``), zones (``zone_exit``, ``zone_enter``, ``loiter``), stationary
(``stationary_end``, ``stationary_start``), abandoned, speed (``speeding``).
"""

from ..rule import RULES
from . import lines, zones, stationary, abandoned, speed  # noqa: F401  (registration order)

__all__ = ["RULES"]
