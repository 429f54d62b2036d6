"""A small file system for tests of a full disk."""

from __future__ import annotations

import os
import shutil
import subprocess
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import pytest


@contextmanager
def small_disk(folder: Path, size: str = "2m") -> Iterator[Path]:
    """A tmpfs of ``size`` mounted on ``folder`` (created; needs root, the test is skipped
    otherwise), unmounted afterwards."""
    folder.mkdir()
    mount = shutil.which("mount")
    proc = (subprocess.run([mount, "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)],
                           capture_output=True, text=True) if mount else None)
    if proc is None or proc.returncode != 0:
        msg = (f"cannot mount a {size} tmpfs (needs root): "
               + (proc.stderr.strip() if proc else "no mount command"))
        if os.environ.get("MOTIONTRACK_REQUIRE_DATA") == "1":
            pytest.fail(msg + " and MOTIONTRACK_REQUIRE_DATA=1")
        pytest.skip(msg)
    try:
        yield folder
    finally:  # lazily when a file on it is still open (a failed test's), so that it always goes
        if subprocess.run(["umount", str(folder)], capture_output=True).returncode != 0:
            subprocess.run(["umount", "-l", str(folder)], capture_output=True)
