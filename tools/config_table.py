"""Print the parameter table of docs/pipeline.md from motiontrack/config.py, or the config's JSON
Schema.

Run: .venv/bin/python tools/config_table.py   (paste the output under "Every parameter")
     .venv/bin/python tools/config_table.py --json-schema   (JSON Schema, draft 2020-12)

The rows come from :func:`motiontrack.config_keys.markdown_table`, which ``motiontrack config``
shares, so the table and the command describe every key in the same words; the JSON Schema from
:func:`motiontrack.schema.json_schema`, for editors that check a config file as it is written.
"""

from __future__ import annotations

import json
import sys

from motiontrack.config import PipelineConfig
from motiontrack.config_keys import markdown_table
from motiontrack.schema import json_schema

if __name__ == "__main__":
    if sys.argv[1:] == ["--json-schema"]:
        print(json.dumps(json_schema(PipelineConfig, title="motiontrack pipeline config"),
                         indent=2))
    else:
        print(markdown_table())
