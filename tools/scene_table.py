"""Print the scene-file tables of docs/analytics.md from the analytics rules.

Run: .venv/bin/python tools/scene_table.py   (paste the tables under "The scene file" and
"Outputs")

The rows come from :mod:`motiontrack.analytics.doc_tables`: every key of the scene file (its top
level and each rule's table) with its type, range, default and meaning as the rules' schemas
declare them, and every event type with its fields. ``motiontrack config --json-schema scene``
prints the same keys as JSON Schema.
"""

from __future__ import annotations

from motiontrack.analytics.doc_tables import event_types_table, scene_keys_table

if __name__ == "__main__":
    print(scene_keys_table())
    print(event_types_table())
