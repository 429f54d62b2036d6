"""Ports and subprocesses for the tests that start servers or whole ``motiontrack`` processes."""

from __future__ import annotations

import signal
import socket
import subprocess


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listened on a moment ago, for a server a test starts."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def communicate_or_dump(proc, timeout: float) -> tuple[str, str]:
    """``proc.communicate(timeout)``; a process still running then (started with
    ``PYTHONFAULTHANDLER=1``) is sent SIGABRT so that its threads' stacks are in the failure."""
    try:
        return proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGABRT)
        out, err = proc.communicate(timeout=30)
        raise AssertionError(f"still running after {timeout} s; its stacks:\n{err[-6000:]}")


class cpu_burners:
    """A busy-loop Python process on each core while the block runs: the machine as loaded as
    a full test run or a busy workstation makes it, for tests of what must hold under load."""

    def __init__(self, count: int | None = None) -> None:
        import os

        self.count = count or os.cpu_count() or 1
        self.procs: list[subprocess.Popen] = []

    def __enter__(self) -> "cpu_burners":
        import sys

        self.procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
                      for _ in range(self.count)]
        return self

    def __exit__(self, *exc) -> None:
        for p in self.procs:
            p.kill()
        for p in self.procs:
            p.wait(timeout=10)


def enable_ctrl_c() -> None:
    """Make SIGINT raise ``KeyboardInterrupt`` in this process again when it was started with
    SIGINT ignored, so that the processes it starts get SIGINT at its default too.

    A command started in the background of a non-interactive shell (``make test &`` in a
    script, a CI step's background job) has SIGINT ignored, and every process it starts
    inherits that: Python then installs no ``KeyboardInterrupt`` handler and a SIGINT a test
    sends to a ``motiontrack`` process (the Ctrl-C tests) does nothing. An ignored signal is
    inherited across ``exec``, a handled one starts at its default."""
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
