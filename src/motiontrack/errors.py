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
