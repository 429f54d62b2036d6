"""``motiontrack ablate``: what each people module contributes (the thesis' figures 4.15/4.16).

Runs the pipeline with the people modules switched on one after another and prints localized
object precision and recall (ξ = 0.75, the thesis' measure) of the tracker output, plus detection
recall/precision, MOTA, IDF1 and HOTA, one row per configuration.
"""

from __future__ import annotations

import argparse
import json
import sys

#: rows of the table: label → overrides (cumulative, as in the thesis)
ROWS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("motion + regions only", ("people.enabled=false", "people.auto_split=false")),
    ("+ head detector", ("people.enabled=true", "people.heads=true", "people.split=false",
                         "people.shapes=false")),
    ("+ head-based splitting", ("people.enabled=true", "people.heads=true", "people.split=true",
                                "people.shapes=false")),
    ("+ active shape tracker", ("people.enabled=true", "people.heads=true", "people.split=true",
                                "people.shapes=true")),
    ("+ shape hypotheses", ("people.enabled=true", "people.heads=true", "people.split=true",
                            "people.shapes=true", "people.hypotheses=true")),
    ("+ HOG in regions", ("people.enabled=true", "people.heads=true", "people.split=true",
                          "people.shapes=true", "people.hypotheses=true", "people.hog=regions",
                          "people.hog_every=5")),
    # not cumulative: the default pipeline, whose regions are split between heads in upright scenes
    ("default (automatic head splitting)", ("people.enabled=false", "people.auto_split=true")),
)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("ablate", help="switch the people modules on one by one and compare",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("source", help="video, image folder or synth:NAME")
    p.add_argument("--gt", help="ground truth (optional for synth: sources)")
    p.add_argument("--config", help="base TOML config")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="STAGE.PARAM=VALUE")
    p.add_argument("--xi", type=float, default=0.75, help="localization threshold (default 0.75)")
    p.add_argument("--rows", help="comma-separated row numbers to run (default all)")
    p.add_argument("-j", "--jobs", type=int, default=1, help="parallel processes")
    p.add_argument("--json", help="also write the table as JSON")
    p.add_argument("--force", action="store_true", help="overwrite an existing --json file")
    p.set_defaults(func=cmd_ablate)


def cmd_ablate(args) -> int:
    from ..config import load_config, to_dict
    from ..errors import ConfigError
    from ..evaluate.sweep import RunSpec, SequenceSpec, execute, parse_param
    from ..io.atomic import atomic_write_text

    if not 0.0 <= args.xi <= 1.0:
        raise ConfigError(f"--xi must be in [0, 1], got {args.xi}")
    from pathlib import Path

    from ..io.atomic import check_writable

    if args.json:
        check_writable([Path(args.json)], args.force)
    base = load_config(args.config, args.overrides)
    rows = list(ROWS)
    if args.rows:
        try:
            pick = [int(r) for r in args.rows.split(",")]
        except ValueError:
            raise ConfigError(f"--rows expects numbers like 1,3, got {args.rows!r}") from None
        if any(not 1 <= r <= len(ROWS) for r in pick):
            raise ConfigError(f"--rows must be between 1 and {len(ROWS)}")
        rows = [ROWS[r - 1] for r in pick]
    seq = SequenceSpec("seq", args.source, args.gt)
    specs = []
    for k, (_label, overrides) in enumerate(rows):
        load_config(None, overrides)  # validate before any run
        params = tuple((key, values[0]) for key, values in map(parse_param, overrides))
        specs.append(RunSpec(run=k, params=params,
                             sequence=seq, base_config=to_dict(base), xi=args.xi))
    results = execute(specs, jobs=args.jobs)
    table = []
    for (label, _), res in zip(rows, results):
        r = res["row"]
        tp, fp, fn = r["TP"], r["FP"], r["FN"]
        table.append({
            "configuration": label,
            "localized_object_precision": r["trk_localized_object_precision"],
            "localized_object_recall": r["trk_localized_object_recall"],
            "recall": tp / (tp + fn) if tp + fn else 0.0,
            "precision": tp / (tp + fp) if tp + fp else 0.0,
            "MOTA": r["MOTA"], "IDF1": r["IDF1"], "HOTA": r["HOTA"],
        })
    cols = ("localized_object_precision", "localized_object_recall", "recall", "precision", "MOTA",
            "IDF1", "HOTA")
    heads = ("LOP", "LOR", "recall", "prec", "MOTA", "IDF1", "HOTA")
    w = max(len(t["configuration"]) for t in table)
    out = [f"{'configuration':<{w}}  " + " ".join(f"{h:>7}" for h in heads)]
    for t in table:
        out.append(f"{t['configuration']:<{w}}  " + " ".join(f"{t[c]:>7.3f}" for c in cols))
    sys.stdout.write("\n".join(out) + "\n")
    if args.json:
        atomic_write_text(args.json, json.dumps(table, indent=2) + "\n")
    return 0
