"""docs/analytics.md lists the scene file's keys and the event types as the rules declare them."""

from __future__ import annotations

from pathlib import Path

from motiontrack.analytics.doc_tables import event_types_table, scene_keys_table
from motiontrack.analytics.rule import RULES

DOC = Path(__file__).resolve().parents[2] / "docs" / "analytics.md"


def test_analytics_doc_has_the_scene_keys_table_the_rules_render():
    assert scene_keys_table() in DOC.read_text(), \
        "docs/analytics.md: paste the first table of `python tools/scene_table.py`"


def test_analytics_doc_has_the_event_types_table_the_rules_render():
    assert event_types_table() in DOC.read_text(), \
        "docs/analytics.md: paste the second table of `python tools/scene_table.py`"


def test_analytics_doc_gives_a_frames_event_order_as_the_rules_rank_it():
    order = ", ".join(f"`{t}`" for t in RULES.event_order())
    assert f"within a frame by track, then {order}" in " ".join(DOC.read_text().split())
