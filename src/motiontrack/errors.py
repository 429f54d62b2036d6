"""Exceptions that the CLI turns into one clear message and a non-zero exit code."""

from __future__ import annotations


class MotionTrackError(Exception):
    """Base for errors caused by the user's input (files, parameters), not by a bug."""

    exit_code = 2


class InputError(MotionTrackError):
    """A source, annotation or config file is missing, empty, corrupt or malformed."""


class ConfigError(MotionTrackError, ValueError):
    """A parameter is unknown or out of its allowed range."""


class SourceError(MotionTrackError):
    """A video source cannot be opened or failed while reading."""

    exit_code = 3


class RunOutcome:
    """How a processing loop ended, so its outputs can be finalised before the error surfaces.

    ``with RunOutcome() as outcome:`` around the loop: an interruption (``KeyboardInterrupt``) or a
    source that failed for good (:class:`SourceError`) ends the block instead of escaping it, and
    is recorded in :attr:`status`, :attr:`interrupted` and :attr:`error`. After the outputs are
    written, :meth:`reraise` lets it escape, so the command still exits with the right code.
    Other exceptions pass through untouched.
    """

    def __init__(self) -> None:
        self.status = "complete"
        self.interrupted = False
        self.error: SourceError | None = None

    def __enter__(self) -> "RunOutcome":
        return self

    def __exit__(self, typ, exc, tb) -> bool:
        if typ is None:
            return False
        if issubclass(typ, KeyboardInterrupt):
            self.interrupted, self.status = True, "interrupted"
            return True
        if issubclass(typ, SourceError):
            self.error, self.status = exc, f"source failed: {exc}"
            return True
        return False

    @property
    def failed(self) -> bool:
        return self.error is not None

    def reraise(self) -> None:
        if self.interrupted:
            raise KeyboardInterrupt
        if self.error is not None:
            raise self.error
