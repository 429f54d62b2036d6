"""Shared test helpers: where the real data lives (env MOTIONTRACK_DATA, default ../shared/data),
and Annotations tables built from rows or from a pipeline run.

Tests that need real data take the ``data`` fixture: they skip with a clear reason when the data is
absent, except under MOTIONTRACK_REQUIRE_DATA=1 (set by .ci/run), where absence fails. The plain
functions here are imported by the test modules (``from conftest import ann, tracks_of``).
"""

from __future__ import annotations

import os
import socket
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import pytest

from motiontrack.types import Annotations, FrameResult

REPO = Path(__file__).resolve().parents[1]


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


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listened on a moment ago, for a server a test starts."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def data():
    """``data("pets09-s2l1", "video.avi")`` → Path (skips or fails when absent)."""
    return require


def ann(rows, *, gt: bool = False, **columns) -> Annotations:
    """Annotations from rows laid out as in a MOTChallenge file: ``(frame, id, x, y, w, h)``,
    optionally followed by column 7 (a prediction's score; with ``gt=True`` the ground truth's
    "consider" flag, non-zero = counts) and, for ground truth, column 8 (the class). No rows give
    an empty table. ``columns`` (``consider=``, ``meta=``, ...) go to
    :meth:`Annotations.from_columns` and take precedence over the rows' columns 7 and 8.
    """
    a = np.asarray(rows, dtype=np.float64)
    a = a.reshape(-1, a.shape[-1] if a.size else 6)
    kw = {}
    if a.shape[1] > 6:
        if gt:
            kw["consider"] = a[:, 6] != 0
        else:
            kw["scores"] = a[:, 6]
    if gt and a.shape[1] > 7:
        kw["classes"] = a[:, 7]
    return Annotations.from_columns(a[:, 0], a[:, 1], a[:, 2:6], **{**kw, **columns})


def tracks_of(results: Iterable[FrameResult]) -> Annotations:
    """The tracks of a pipeline run as Annotations: one row ``(frame index + 1, track id, box)``
    per track in each result's ``tracks``, that is what each frame reports as it is processed
    (the backfilled rows of ``FrameResult.earlier`` are left out).

    ``results`` is a run (``motiontrack.track(...)``, ``motiontrack.pipeline.run(...)``: read to
    its end, then closed) or any iterable of :class:`FrameResult`.
    """
    try:
        rows = [(r.index + 1, t.id, *t.box.as_array()) for r in results for t in r.tracks]
    finally:
        close = getattr(results, "close", None)
        if close is not None:
            close()
    return ann(rows)


def communicate_or_dump(proc, timeout: float) -> tuple[str, str]:
    """``proc.communicate(timeout)``; a process still running then (started with
    ``PYTHONFAULTHANDLER=1``) is sent SIGABRT so that its threads' stacks are in the failure."""
    import signal
    import subprocess

    try:
        return proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGABRT)
        out, err = proc.communicate(timeout=30)
        raise AssertionError(f"still running after {timeout} s; its stacks:\n{err[-6000:]}")
