"""The command line as a whole: help text of every option, the logging options in any position,
and log lines next to a progress bar."""

from __future__ import annotations

import argparse
import io
import logging

import pytest

from motiontrack.cli import _configure_logging, build_parser, command_module


def _parsers(parser: argparse.ArgumentParser, path: str = "motiontrack"):
    """``(command path, parser)`` for the top-level parser and every (nested) command."""
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            seen: set[int] = set()
            for name, child in action.choices.items():
                if id(child) not in seen:
                    seen.add(id(child))
                    yield from _parsers(child, f"{path} {name}")


def test_every_option_of_every_command_has_help():
    missing = []
    for path, parser in _parsers(build_parser()):
        for action in parser._actions:
            if isinstance(action, (argparse._HelpAction, argparse._VersionAction)):
                continue
            if not (action.help or "").strip():
                missing.append(f"{path} {'/'.join(action.option_strings) or action.dest}")
            for choice in getattr(action, "_choices_actions", ()):   # each command's own line
                if not (choice.help or "").strip():
                    missing.append(f"{path} {choice.dest}")
    assert len(list(_parsers(build_parser()))) > 15    # the walk reaches the commands
    assert missing == []


@pytest.mark.parametrize("argv, quiet, debug", [
    (["list"], False, False),
    (["-q", "list"], True, False),
    (["list", "-q"], True, False),
    (["list", "--quiet"], True, False),
    (["list", "--debug"], False, True),
    (["--debug", "list"], False, True),
    (["-q", "track", "synth:walker"], True, False),
    (["track", "synth:walker", "-q", "--debug"], True, True),
    (["calibrate", "show", "cam.xml", "img.png", "-o", "x.png", "-q"], True, False),
    (["--debug", "calibrate", "-q", "show", "cam.xml", "img.png", "-o", "x.png"], True, True),
])
def test_logging_options_work_before_and_after_the_command(argv, quiet, debug):
    args = build_parser().parse_args(argv)
    assert (args.quiet, args.debug) == (quiet, debug)


def test_each_command_module_adds_the_command_named_after_it():
    """What lets a command line that names a command build that command's parser alone."""
    full = build_parser()
    commands = next(a for a in full._actions if isinstance(a, argparse._SubParsersAction)).choices
    for name, parser in commands.items():
        module = command_module([name])
        assert module == name.replace("-", "_"), name
        alone = build_parser(module)
        only = next(a for a in alone._actions if isinstance(a, argparse._SubParsersAction))
        assert list(only.choices) == [name]
        assert only.choices[name].format_help() == parser.format_help()


@pytest.mark.parametrize("argv, module", [
    (["track", "x.mp4"], "track"),
    (["-q", "--debug", "evaluate-events", "a", "b"], "evaluate_events"),
    (["calibrate", "show"], "calibrate"),
    (["--help"], None),
    ([], None),
    (["no-such-command"], None),
    (["_common"], None),        # a helper module, not a command
    (["--", "track"], None),
    (["../track"], None),
])
def test_the_command_a_command_line_names(argv, module):
    assert command_module(argv) == module


def test_an_unknown_command_is_refused_with_the_list_of_commands(capsys):
    from motiontrack.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["trak", "x.mp4"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'trak'" in err and "'track'" in err and "'evaluate'" in err


def test_every_command_takes_the_logging_options_after_it():
    parser = build_parser()
    for path, sub in _parsers(parser):
        if path == "motiontrack":
            continue
        options = {s for a in sub._actions for s in a.option_strings}
        assert {"-q", "--quiet", "--debug"} <= options, path


def test_log_lines_do_not_break_the_progress_bar(capsys):
    """A record logged while a bar is shown is a line of its own (the bar is cleared first and
    drawn again after it), not text appended to the bar."""
    from tqdm import tqdm

    _configure_logging(debug=False, quiet=False)
    import sys

    with tqdm(total=10, file=sys.stderr, disable=False, ncols=60, mininterval=0, miniters=1) as bar:
        bar.update(3)
        logging.getLogger("motiontrack.test").warning("stream %s lost", "a\nb")
        bar.update(3)
    err = capsys.readouterr().err
    lines = [seg for line in err.split("\n") for seg in line.split("\r")]
    log_lines = [s for s in lines if "lost" in s]
    # one escaped line, starting where a line starts: the bar's text is not in front of it
    assert log_lines == ["motiontrack: WARNING: stream a\\nb lost"]
    assert err.index("30%") < err.index("lost") < err.rindex("60%")   # the bar goes on below


def test_log_lines_without_a_bar_are_written_as_usual():
    stream = io.StringIO()
    _configure_logging(debug=False, quiet=False)
    handler = logging.getLogger("motiontrack").handlers[0]
    handler.setStream(stream)
    logging.getLogger("motiontrack.test").info("plain")
    assert stream.getvalue() == "motiontrack: INFO: plain\n"
