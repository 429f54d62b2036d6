"""``motiontrack report DIR -o report.html``: a self-contained HTML page of a sweep study."""

from __future__ import annotations

import argparse
from pathlib import Path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "report", help="one self-contained HTML page of a sweep study (readable offline)",
        description="Meta data, tables, figures (embedded) and links to the clips of the study in DIR.")
    p.add_argument("study", metavar="DIR", help="a `motiontrack sweep` output folder")
    p.add_argument("-o", "--out", help="HTML file (default: DIR/report.html; - for standard "
                                       "output, links relative to the current folder)")
    p.add_argument("--force", action="store_true", help="overwrite an existing report")
    p.set_defaults(func=cmd_report)


def cmd_report(args) -> int:
    from ..errors import check_output_path, printable
    from ..io.atomic import is_stdout, writing_outputs
    from ..studies.report import write_report

    out = args.out or str(Path(args.study) / "report.html")
    if not is_stdout(out):
        check_output_path(out, "-o")  # not a folder, in a folder that can be written
    # the report's folder is locked while it is written: into a study a sweep is still running
    # in, a report is refused as any second writer there is
    with writing_outputs([out], args.force):
        _note_running_sweep(Path(args.study), out)
        written = write_report(args.study, out)
    if not is_stdout(out):
        print(f"outputs   {printable(written)}")
    return 0


def _note_running_sweep(study, out: str) -> None:
    """Warn when a sweep still holds ``study`` (the report shows the runs it has finished)."""
    import logging
    import os

    from ..errors import InputError
    from ..io.atomic import OutputLock, is_stdout

    if not study.is_dir() or (not is_stdout(out)
                              and os.path.samefile(Path(os.path.abspath(out)).parent, study)):
        return   # a missing study is reported by the reader; our own lock is not a sweep's
    try:
        OutputLock(study).release()
    except InputError as exc:
        logging.getLogger("motiontrack.report").warning(
            "%s: the report shows the runs finished so far", str(exc).split(";")[0])
