"""Helpers shared by the command modules (argument types, signals, progress, GT loading)."""

from __future__ import annotations

import argparse
import atexit
import logging
import os
import signal
import sys
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Mapping

from ..config_flags import flag, flag_overrides
from ..errors import ConfigError


def frame_range(text: str) -> tuple[int, int | None]:
    """``A:B`` (inclusive, 1-based frame numbers), ``A:`` or ``:B``."""
    if ":" not in text:
        raise ConfigError(f"expected a frame range A:B, got {text!r}")
    a, b = text.split(":", 1)
    try:
        lo = int(a) if a.strip() else 1
        hi = int(b) if b.strip() else None
    except ValueError:
        raise ConfigError(f"expected integers in the frame range A:B, got {text!r}") from None
    if lo < 1 or (hi is not None and hi < lo):
        raise ConfigError(f"frame range must satisfy 1 <= A <= B, got {text!r}")
    return lo, hi


class GracefulStop:
    """SIGINT/SIGTERM handlers that ask the running job to stop after the current frame, or at
    once while its source waits for one (a live stream backing off, reconnecting or stalled).

    ``stop()`` tells whether a stop was requested; the job polls it after each frame and hands
    it to the source (:attr:`~motiontrack.io.sources.Source.stop_requested`). A second signal
    raises ``KeyboardInterrupt`` at once, for a user who really wants out.
    """

    def __init__(self) -> None:
        self.requested = False
        self._old: dict[int, object] = {}

    def _handler(self, signum, frame):  # pragma: no cover - exercised in subprocess tests
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True

    def stop(self) -> bool:
        return self.requested

    def __enter__(self) -> "GracefulStop":
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                self._old[sig] = signal.signal(sig, self._handler)
            except ValueError:  # not in the main thread: keep the defaults
                pass
        return self

    def __exit__(self, *exc) -> None:
        for sig, old in self._old.items():
            signal.signal(sig, old)


@dataclass(frozen=True)
class FrameLoop:
    """What a frame loop of a command needs: ``update(n)`` advances the progress bar, ``stop()``
    tells whether SIGINT/SIGTERM asked to stop, and ``tick()`` does both after a complete frame,
    raising ``KeyboardInterrupt`` when a stop was asked (the command then finalises its outputs
    with the frames done so far)."""

    update: Callable[[int], Any]
    stop: Callable[[], bool]

    def tick(self) -> None:
        self.update(1)
        if self.stop():
            raise KeyboardInterrupt


@contextmanager
def frame_loop(total: int | None) -> Iterator[FrameLoop]:
    """:class:`GracefulStop` signal handlers and a frame progress bar on stderr (hidden when
    stderr is not a terminal) for the duration of a command's frame loop.

    A stopped loop (``KeyboardInterrupt``, which the command turns into exit code 130) whose live
    source was left inside an OpenCV call exits without waiting for that call
    (:func:`_exit_now_if_still_reading`)."""
    with GracefulStop() as stop, _progress_bar(total) as update:
        try:
            yield FrameLoop(update, stop.stop)
        except KeyboardInterrupt:
            from ..io.sources import blocked_live_sources

            blocked = blocked_live_sources()
            if blocked:
                atexit.register(_exit_now_if_still_reading, blocked, 130)
            raise


@contextmanager
def _progress_bar(total: int | None) -> Iterator[Callable[[int], Any]]:
    """The ``update(n)`` of a tqdm frame bar on stderr. When stderr is not a terminal the bar is
    hidden (tqdm's ``disable=None``), and tqdm, which takes longer to import than a short run
    takes to start, is not imported at all."""
    if hasattr(sys.stderr, "isatty") and not sys.stderr.isatty():
        yield lambda n=1: None
        return
    from tqdm import tqdm

    with tqdm(total=total, unit="frame", disable=None, file=sys.stderr,
              dynamic_ncols=True) as bar:
        yield bar.update


def _exit_now_if_still_reading(sources: list, code: int) -> None:
    """Exit hook of a stopped command whose outputs are final: when one of ``sources`` is still
    inside an OpenCV call (a read of a silent stream lasts up to its read timeout, and cannot be
    interrupted), end the process now with ``code``. Waiting is the only other safe course: the
    interpreter must not finalise while the call is pending (it aborts when the call returns).
    Registered after the live sources' own exit hook, so it runs before it."""
    if not any(src.in_opencv_call for src in sources):
        return
    logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):   # closed or broken: nothing more to say
            pass
    os._exit(code)


def max_pixels_option(p: argparse.ArgumentParser) -> None:
    """``--max-pixels N`` of the commands that read pictures outside a pipeline config."""
    p.add_argument("--max-pixels", type=int, default=50_000_000,
                   help="refuse a picture (its header) or video (its container) of more pixels, "
                        "before decoding it (50000000; at most 2**30)")


def checked_max_pixels(args: argparse.Namespace) -> int:
    if not 1 <= args.max_pixels <= 2**30:
        raise ConfigError(f"--max-pixels must be in [1, {2**30}], got {args.max_pixels}")
    return args.max_pixels


def accuracy_line(a: Mapping[str, Any],
                  keys: tuple[str, ...] = ("HOTA", "MOTA", "IDF1", "recall", "precision")) -> str:
    """The ``accuracy`` line of a command's printed summary, ending with the scoring
    convention when ``a`` names one (``(scoring trackeval)``)."""
    return ("accuracy  " + "  ".join(f"{k} {a[k]:.3f}" for k in keys if k in a)
            + (f"  IDSW {int(a['IDSW'])}" if "IDSW" in a else "")
            + (f"  (scoring {a['scoring']})" if "scoring" in a else ""))


def add_scoring_option(parser) -> None:
    """``--scoring``: how zero-marked ground truth counts (the same option on every command
    that scores tracks)."""
    from ..evaluate.scoring import DEFAULT_SCORING, SCORING, SCORING_HELP

    parser.add_argument("--scoring", choices=tuple(SCORING), default=DEFAULT_SCORING,
                        action=_GivenStore, help=SCORING_HELP)


class _GivenStore(argparse.Action):
    """Store the value and remember that it was given (``args.<dest>_given``), so a command can
    refuse an option that would have no effect instead of ignoring it."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        setattr(namespace, f"{self.dest}_given", True)


def given(args, dest: str) -> bool:
    """Whether option ``dest`` (stored with :class:`_GivenStore`) was on the command line."""
    return bool(getattr(args, f"{dest}_given", False))


#: help of ``--fps``, the option of every command that reads video
FPS_HELP = flag("--fps").meaning


def out_help(command: str) -> str:
    """Help of ``-o`` of a command that writes a run folder."""
    return (f"output folder (default: a new folder runs/{command}/NAME named after the source: "
            f"video.mp4 -> runs/{command}/video, then video-2, ...; outputs already in a folder "
            "given here are replaced only with --force)")


def output_folder(args, command: str):
    """``-o`` when given, else a new run folder (:func:`~motiontrack.run.folders.new_run_folder`)."""
    if args.out is not None:
        return args.out
    from ..run.folders import new_run_folder

    return new_run_folder(command, args.source)


def run_overrides(args, dests: tuple[str, ...] = ("start", "max_frames", "fps", "codec")
                  ) -> list[str]:
    """``--set`` overrides, then those of the options ``dests`` that stand for config keys
    (:data:`motiontrack.config_flags.FLAGS`: ``--start``, ``--max-frames``, ``--fps`` and
    ``--codec`` by default, the options ``track`` and ``flow`` share), in the table's order."""
    if getattr(args, "codec", None) and "codec" in dests:
        from ..io.video import check_codec

        check_codec(args.codec)   # one message naming the codecs this installation encodes
    return list(args.overrides) + flag_overrides(args, dests)


class CodecOption(argparse.Action):
    """``--codec NAME``: its help lists the codecs this installation can encode, found only
    when the help is shown, from the cached probe of this installation
    (:mod:`motiontrack.io.codec_cache`) (``p.add_argument("--codec", action=CodecOption)``)."""

    def __init__(self, option_strings, dest, default=None, **kwargs) -> None:
        kwargs.pop("help", None)
        super().__init__(option_strings, dest, default=default, metavar="NAME", **kwargs)

    @property
    def help(self) -> str:
        from ..io.codec_cache import encodable_codec_names

        return (f"video codec, one this installation can encode: "
                f"{', '.join(encodable_codec_names())} (default {self.default or 'vp80'}; "
                "`motiontrack list` says what each is)")

    @help.setter
    def help(self, value) -> None:   # argparse sets it; the text is made when shown
        pass

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        setattr(namespace, self.dest, values)


def read_gt(path: str):
    """Read a ground-truth file in any supported annotation format (MOT CSV read as gt), with
    the length of a ``seqinfo.ini`` beside it
    (:func:`~motiontrack.io.annotations.read_ground_truth`)."""
    from ..io.annotations import read_ground_truth

    return read_ground_truth(path)


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Treat SIGTERM like Ctrl-C (``KeyboardInterrupt``), for commands that finalise their
    outputs in a ``KeyboardInterrupt`` handler."""

    def handler(signum, frame):  # pragma: no cover - exercised in subprocess tests
        raise KeyboardInterrupt

    try:
        old = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not in the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)
