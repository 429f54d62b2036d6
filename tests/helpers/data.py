"""Where the real data lives (env ``MOTIONTRACK_DATA``, default ``../shared/data``).

A test that needs real data takes the ``data`` fixture (tests/conftest.py) or calls
:func:`require`: it skips with a clear reason when the data is absent, except under
``MOTIONTRACK_REQUIRE_DATA=1`` (set by .ci/run), where absence fails.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def data_root() -> Path:
    return Path(os.environ.get("MOTIONTRACK_DATA", REPO.parent / "shared" / "data")).resolve()


def require(*parts: str) -> Path:
    """Path to a file/folder under the data root, or skip/fail when it is missing."""
    p = data_root().joinpath(*parts)
    if not p.exists():
        msg = f"real data not found: {p} (set MOTIONTRACK_DATA)"
        if os.environ.get("MOTIONTRACK_REQUIRE_DATA") == "1":
            pytest.fail(msg + " and MOTIONTRACK_REQUIRE_DATA=1")
        pytest.skip(msg)
    return p
