"""``motiontrack ablate``: what each people module contributes (the thesis' figures 4.15/4.16).

Runs the pipeline with the people modules switched on one after another and prints localized
object precision and recall (ξ = 0.75, the thesis' measure) of the tracker output, plus detection
recall/precision, MOTA, IDF1 and HOTA, one row per configuration.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys

log = logging.getLogger("motiontrack")


def register(sub: argparse._SubParsersAction) -> None:
    from ._common import add_scoring_option

    p = sub.add_parser("ablate", help="switch the people modules on one by one and compare",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("source", help="video, image folder or synth:NAME")
    p.add_argument("--gt", help="ground truth (optional for synth: sources)")
    p.add_argument("--config", help="base TOML config")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="STAGE.PARAM=VALUE",
                   help="override one base config field, e.g. --set motion.method=knn (repeatable)")
    p.add_argument("--xi", type=float, default=0.75, help="localization threshold (default 0.75)")
    add_scoring_option(p)
    p.add_argument("--rows", help="comma-separated row numbers to run (default all)")
    p.add_argument("-j", "--jobs", type=int, default=1, help="parallel processes")
    p.add_argument("--json", help="also write the table as JSON (- for standard output; the "
                                  "printed table then goes to standard error)")
    p.add_argument("--force", action="store_true", help="overwrite an existing --json file")
    p.set_defaults(func=cmd_ablate)


def cmd_ablate(args) -> int:
    from pathlib import Path

    from ..config import load_config
    from ..config_activity import warn_inactive_overrides
    from ..io.atomic import atomic_write_text, check_writable, is_stdout
    from ..studies.ablate import (AblationInterrupted, format_table, row_settings,
                                  run_ablation, select_rows)
    from ._common import sigterm_as_interrupt

    if args.json:
        check_writable([Path(args.json)], args.force)
    rows = select_rows(args.rows)
    cfg = load_config(args.config, args.overrides)
    # a --set key is in effect when one of the rows switches it on
    warn_inactive_overrides(cfg, args.overrides, points=row_settings(rows))
    code = 0
    try:
        # SIGTERM stops the rows as Ctrl-C does: the finished ones are printed and written
        with sigterm_as_interrupt():
            table = run_ablation(args.source, args.gt, cfg, rows,
                                 xi=args.xi, jobs=args.jobs, scoring=args.scoring)
    except AblationInterrupted as stop:
        if not stop.table:
            raise
        log.warning("%s: the finished rows follow", stop)
        table, code = stop.table, 130
    (sys.stderr if is_stdout(args.json) else sys.stdout).write(format_table(table))
    if args.json:
        atomic_write_text(args.json, json.dumps(table, indent=2) + "\n")
    return code
