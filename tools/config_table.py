"""Print the parameter table of docs/pipeline.md from motiontrack/config.py.

Run: .venv/bin/python tools/config_table.py   (paste the output under "Every parameter")
"""

from __future__ import annotations

import dataclasses

from motiontrack.config import PipelineConfig


def rows(cls, prefix=""):
    for f in dataclasses.fields(cls):
        default = f.default if f.default is not dataclasses.MISSING else f.default_factory()
        if dataclasses.is_dataclass(default):
            yield from rows(type(default), f"{prefix}{f.name}.")
            continue
        m = f.metadata
        allowed = ""
        if m.get("choices"):
            allowed = " / ".join(map(str, m["choices"]))
        elif m.get("lo") is not None or m.get("hi") is not None:
            lo = m.get("lo") if m.get("lo") is not None else "-inf"
            hi = m.get("hi") if m.get("hi") is not None else "inf"
            allowed = f"[{lo}, {hi}]"
        if m.get("odd"):
            allowed += " odd or 0"
        yield f"| `{prefix}{f.name}` | `{default!r}` | {allowed} | {m.get('doc', '')} |"


if __name__ == "__main__":
    print("| key | default | allowed | meaning |\n|---|---|---|---|")
    for row in rows(PipelineConfig):
        print(row)
