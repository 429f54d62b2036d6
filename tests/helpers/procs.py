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
