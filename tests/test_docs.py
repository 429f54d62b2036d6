"""Documentation stays in step with the code."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from motiontrack.config import PipelineConfig

DOCS = Path(__file__).resolve().parents[1] / "docs"


def _keys(cls, prefix=""):
    for f in dataclasses.fields(cls):
        default = f.default if f.default is not dataclasses.MISSING else f.default_factory()
        if dataclasses.is_dataclass(default):
            yield from _keys(type(default), f"{prefix}{f.name}.")
        else:
            yield f"{prefix}{f.name}", default


def test_pipeline_doc_lists_every_parameter_with_its_default():
    text = (DOCS / "pipeline.md").read_text()
    missing = [k for k, v in _keys(PipelineConfig) if f"| `{k}` | `{v!r}` |" not in text]
    assert not missing, f"docs/pipeline.md lacks or has stale rows for: {missing}"
