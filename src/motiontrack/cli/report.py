"""``motiontrack report DIR -o report.html``: a self-contained HTML page of a sweep study."""

from __future__ import annotations

import argparse


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
    from pathlib import Path

    from ..errors import check_output_path, printable
    from ..io.atomic import check_writable, is_stdout
    from ..studies.report import write_report

    out = args.out or str(Path(args.study) / "report.html")
    if not is_stdout(out):
        check_output_path(out, "-o")  # not a folder, in a folder that can be written
    check_writable([Path(out)], args.force)
    written = write_report(args.study, out)
    if not is_stdout(out):
        print(f"outputs   {printable(written)}")
    return 0
