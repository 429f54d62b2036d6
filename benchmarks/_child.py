"""Whole-process measurements: a command run as a fresh process, timed from its start to its exit,
as a user who types it pays for it (interpreter start, imports, reading, writing, exit)."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class ChildRun:
    """One run of a command: wall time from before the process is started until it has been
    reaped, CPU time (user + sys) and peak resident memory of the process (each including the
    children it waited for), and what it printed."""

    wall_s: float
    cpu_s: float
    peak_rss_mb: float
    stdout: str
    stderr: str


def motiontrack_command() -> list[str]:
    """The ``motiontrack`` command of this interpreter's environment: its console script when it
    is installed beside the interpreter, else ``python -m motiontrack``."""
    exe = Path(sys.executable).with_name("motiontrack")
    return [str(exe)] if exe.is_file() else [sys.executable, "-m", "motiontrack"]


def cache_bytecode(work: Path) -> None:
    """Let the children keep compiled bytecode (in ``work``), as an installed package has it: a
    shell with ``PYTHONDONTWRITEBYTECODE=1`` would otherwise make every start recompile
    motiontrack's sources. Run each command once before timing it, to fill the cache."""
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    os.environ["PYTHONPYCACHEPREFIX"] = str(Path(work) / "bytecode")


def run_child(argv: list[str]) -> ChildRun:
    """Run ``argv`` to its end and measure it (:class:`ChildRun`); exit with the command's own
    message when it fails. Its output goes to files, read once it has exited, so the parent does
    nothing while it runs."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(argv, stdout=out, stderr=err, stdin=subprocess.DEVNULL)
        # os.wait4 reaps the child and returns its own resource usage (getrusage(RUSAGE_CHILDREN)
        # would be the running total over every child so far, and its maxrss the largest of them)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        stdout = out.read().decode("utf-8", "replace")
        stderr = err.read().decode("utf-8", "replace")
    if proc.returncode != 0:
        sys.exit(f"{' '.join(map(str, argv))}\nexited with {proc.returncode}:\n{stderr[-3000:]}")
    # ru_maxrss is in KiB on Linux
    return ChildRun(wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0, stdout, stderr)
