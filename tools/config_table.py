"""Print the parameter table of docs/pipeline.md from motiontrack/config.py.

Run: .venv/bin/python tools/config_table.py   (paste the output under "Every parameter")

The rows come from :func:`motiontrack.config_keys.markdown_table`, which ``motiontrack config``
shares, so the table and the command describe every key in the same words.
"""

from __future__ import annotations

from motiontrack.config_keys import markdown_table

if __name__ == "__main__":
    print(markdown_table())
