"""The messages FFmpeg and OpenCV write to stderr themselves: silenced, so that an unreadable or
damaged video gives motiontrack's one line alone, and shown with ``--debug``.

FFmpeg (inside OpenCV's video backend) prints lines such as ``[mov,mp4,m4a,3gp,3g2,mj2 @ 0x…]
moov atom not found`` or ``[h264 @ 0x…] error while decoding MB`` beside the error or warning
motiontrack gives for the same file, and once per frame for a damaged stream. OpenCV's backend
reads its FFmpeg log level from ``OPENCV_FFMPEG_LOGLEVEL`` (an FFmpeg ``AV_LOG_*`` number) when it
first opens a video, and its own logger reads ``OPENCV_LOG_LEVEL`` when it starts; both are set
in ``os.environ`` so that every process started from this one (``serve``'s camera processes, the
workers of a sweep) inherits them. A level the user set in the environment is kept. PyAV, which
only writes videos here, keeps FFmpeg's messages to itself unless told otherwise.

:func:`quiet` runs when :mod:`motiontrack.io.sources` is imported, before any video is opened;
the command line calls :func:`verbose` for ``--debug``.
"""

from __future__ import annotations

import os

import cv2

__all__ = ["quiet", "verbose", "FFMPEG_ENV", "OPENCV_ENV"]

FFMPEG_ENV = "OPENCV_FFMPEG_LOGLEVEL"
OPENCV_ENV = "OPENCV_LOG_LEVEL"
#: FFmpeg's AV_LOG_QUIET and AV_LOG_WARNING
_FFMPEG_QUIET, _FFMPEG_WARNING = "-8", "24"

# the levels the user gave in the environment; the quiet ones are those a parent process
# running motiontrack set (serve's camera processes and a sweep's workers inherit them), which
# --debug overrides
_USER = {name: os.environ.get(name) for name in (FFMPEG_ENV, OPENCV_ENV)
         if os.environ.get(name) not in (None, _FFMPEG_QUIET, "SILENT")}
_verbose = False


def _set(ffmpeg: str, opencv: str, opencv_level: int) -> None:
    if FFMPEG_ENV not in _USER:
        os.environ[FFMPEG_ENV] = ffmpeg
    if OPENCV_ENV not in _USER:
        os.environ[OPENCV_ENV] = opencv
        cv2.utils.logging.setLogLevel(opencv_level)


def quiet() -> None:
    """No message of FFmpeg or OpenCV on stderr (unless the user's environment or
    :func:`verbose` asks for them)."""
    if _verbose:
        return
    _set(_FFMPEG_QUIET, "SILENT", cv2.utils.logging.LOG_LEVEL_SILENT)


def verbose() -> None:
    """FFmpeg's and OpenCV's warnings and errors on stderr (``--debug``). FFmpeg's level takes
    effect when it has not opened a video yet in this process."""
    global _verbose
    _verbose = True
    _set(_FFMPEG_WARNING, "WARNING", cv2.utils.logging.LOG_LEVEL_WARNING)
