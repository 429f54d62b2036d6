"""The command line. Only this package parses arguments, configures logging, shows progress bars
and exits. Each sub-module that defines ``register(subparsers)`` adds the command named after it
(``cli/evaluate_events.py`` adds ``evaluate-events``, nested commands under it); they are
discovered automatically so that commands live in their own small modules. A command line that
names a command builds that command's parser alone: importing and building every command's parser
would take a tenth of a second off each run's start.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import importlib.util
import logging
import os
import pkgutil
import sys
import traceback

from ..errors import MotionTrackError, describe_os_error, printable
from ..version import __version__

log = logging.getLogger("motiontrack")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every command, or of ``command`` alone (its module name,
    :func:`command_module`): what a command line that names it needs."""
    parser = argparse.ArgumentParser(
        prog="motiontrack",
        description="Find and follow moving objects in video; evaluate trackers against ground truth.",
    )
    parser.add_argument("--version", action="version", version=f"motiontrack {__version__}")
    _add_logging_options(parser, default=False)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND",
                                help="what to do (motiontrack COMMAND --help for its options)")
    names = ([command] if command is not None else
             sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_")))
    for name in names:
        module = importlib.import_module(f"{__name__}.{name}")
        if hasattr(module, "register"):
            module.register(sub)
    for command in _subcommand_parsers(parser):
        # the logging options also after the command (`motiontrack track X -q`); SUPPRESS keeps
        # a command's parser from resetting a value given before the command
        _add_logging_options(command, default=argparse.SUPPRESS)
    return parser


def command_module(argv: list[str]) -> str | None:
    """The module of the command ``argv`` names (its first argument that is not an option), None
    when it names none of them (the whole parser then gives the help or the error)."""
    for arg in argv:
        if arg == "--":
            return None
        if not arg.startswith("-"):
            name = arg.replace("-", "_")
            if not name.isidentifier() or name.startswith("_"):
                return None
            try:
                found = importlib.util.find_spec(f"{__name__}.{name}") is not None
            except (ImportError, ValueError):
                return None
            return name if found else None
    return None


def _add_logging_options(parser: argparse.ArgumentParser, default: object) -> None:
    parser.add_argument("--debug", action="store_true", default=default,
                        help="show tracebacks and debug logging")
    parser.add_argument("-q", "--quiet", action="store_true", default=default,
                        help="only warnings and errors")


def _subcommand_parsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    """Every command's parser under ``parser``, nested ones (``calibrate lines``) included,
    each once (an alias names the same parser)."""
    found: dict[int, argparse.ArgumentParser] = {}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                if id(child) not in found:
                    found[id(child)] = child
                    found.update((id(p), p) for p in _subcommand_parsers(child))
    # not list(...): importing the command module cli/list.py binds the name `list` here
    return [p for p in found.values()]


def _configure_logging(debug: bool, quiet: bool) -> None:
    level = logging.DEBUG if debug else (logging.WARNING if quiet else logging.INFO)
    handler = _BarAwareHandler(sys.stderr)
    handler.setFormatter(_OneLineFormatter("motiontrack: %(levelname)s: %(message)s"
                                           if not debug else "%(name)s: %(levelname)s: %(message)s"))
    root = logging.getLogger("motiontrack")
    root.handlers[:] = [handler]
    root.setLevel(level)
    root.propagate = False
    if debug:   # FFmpeg's and OpenCV's own messages too (only here: it imports cv2)
        from ..io.native_logs import verbose

        verbose()


#: failed file operations that are the machine's state, not a bug, even without a file name
_ENVIRONMENT_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES,
                                 errno.EPERM})


class _OneLineFormatter(logging.Formatter):
    """Log messages with control characters escaped (:func:`~motiontrack.errors.printable`): a
    file name or file content in a message cannot start a line that looks like another message."""

    def formatMessage(self, record: logging.LogRecord) -> str:  # noqa: N802 (logging API)
        return printable(super().formatMessage(record))


class _BarAwareHandler(logging.StreamHandler):
    """A stream handler that keeps log lines and progress bars apart: while a tqdm bar is shown,
    a record clears the bar, is written on a line of its own and the bar is drawn again below it
    (``tqdm.write``); otherwise the record is written as usual. The record is formatted first, so
    the line keeps :class:`_OneLineFormatter`'s escaping."""

    def emit(self, record: logging.LogRecord) -> None:
        std = sys.modules.get("tqdm.std")  # not imported: no bar can be on screen
        if std is None or not getattr(std.tqdm, "_instances", None):
            super().emit(record)
            return
        try:
            std.tqdm.write(self.format(record), file=self.stream)
            self.flush()
        except RecursionError:
            raise
        except Exception:  # what logging.StreamHandler does with a failed write
            self.handleError(record)


def _open_standard_streams() -> None:
    """Open on the null device each standard stream the caller closed (``2>&-``): Python then
    has no ``sys.stderr`` for messages and progress bars, and the next file opened would take
    descriptor 2 and receive whatever a library writes there."""
    for fd, name, mode in ((0, "stdin", "r"), (1, "stdout", "w"), (2, "stderr", "w")):
        try:
            os.fstat(fd)
            continue
        except OSError:
            null = os.open(os.devnull, os.O_RDWR)
        if null != fd:
            os.dup2(null, fd)
            os.close(null)
        if getattr(sys, name) is None:
            setattr(sys, name, open(fd, mode, closefd=False))


def main(argv: list[str] | None = None) -> int:
    _open_standard_streams()
    # not list(argv): importing the command module cli/list.py binds the name `list` here
    argv = sys.argv[1:] if argv is None else [*argv]
    parser = build_parser(command_module(argv))
    args = parser.parse_args(argv)
    _configure_logging(args.debug, args.quiet)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return 2
    try:
        code = args.func(args)
        return int(code or 0)
    except MotionTrackError as exc:
        if args.debug:
            traceback.print_exc()
        print(f"motiontrack: error: {printable(exc)}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("motiontrack: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 141
    except OSError as exc:
        if exc.filename is None and exc.errno not in _ENVIRONMENT_ERRNOS:
            return _internal_error(exc, args.debug)
        # a file or folder the user named cannot be read or written, or the disk is full:
        # their input or their machine, not a bug
        if args.debug:
            traceback.print_exc()
        print(f"motiontrack: error: {describe_os_error(exc)}", file=sys.stderr)
        return 2
    except Exception as exc:  # a bug: still one line unless --debug
        return _internal_error(exc, args.debug)


def _internal_error(exc: Exception, debug: bool) -> int:
    """Report a bug: the traceback with ``--debug``, otherwise one line; exit code 1."""
    if debug:
        traceback.print_exc()
    else:
        print(f"motiontrack: internal error: {type(exc).__name__}: {printable(exc)} (run with "
              "--debug for the traceback)", file=sys.stderr)
    return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
