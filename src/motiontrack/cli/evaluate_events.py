"""``motiontrack evaluate-events``: event precision, recall, F1 and count errors against ground
truth."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "evaluate-events",
        help="score scene-analytics events (line crossings, zone dwell, loitering, ...) against "
             "ground-truth events",
        description="Match predicted events to ground-truth events of the same type, line and "
                    "direction or zone, one to one within a time tolerance, and report TP, FP, "
                    "FN, precision, recall, F1 and the count error (predicted - ground truth) "
                    "per line, zone and direction, per type and in total (docs/analytics.md). "
                    "GT and PRED are events files (events.jsonl); with --scene, any other file "
                    "is a tracks file analysed first, as `analyze` does.")
    p.add_argument("--gt", required=True, type=Path, help="ground-truth events (or tracks) file")
    p.add_argument("--pred", required=True, type=Path, help="predicted events (or tracks) file")
    p.add_argument("--tolerance-s", type=float, default=1.0,
                   help="largest time difference of a match, seconds (default 1.0)")
    p.add_argument("--scene", type=Path, default=None,
                   help="scene file (TOML) to analyse a tracks file given as --gt or --pred")
    p.add_argument("--fps", type=float, default=None,
                   help="frames per second of tracks files (default: stated beside them, as "
                        "for analyze)")
    p.add_argument("--camera", type=Path, default=None,
                   help="camera file for a scene in metres (tracks files only)")
    p.add_argument("--json", type=Path, default=None,
                   help="write the scores as JSON (- for standard output; the table then goes "
                        "to standard error)")
    p.add_argument("--force", action="store_true", help="overwrite an existing --json file")
    p.set_defaults(func=run)


def _ratio(v: float | None) -> str:
    return "-" if v is None else f"{100 * v:.1f}"


def format_table(result) -> str:
    """One row per line/zone/direction group, then per type and the total."""
    head = (f"{'events':<34} {'GT':>5} {'Pred':>5} {'TP':>5} {'FP':>5} {'FN':>5} {'Prec%':>6} "
            f"{'Rec%':>6} {'F1%':>6} {'CntErr':>6} {'|dt|s':>6}")

    def row(label: str, s) -> str:
        dt = "-" if s.mean_abs_dt_s is None else f"{s.mean_abs_dt_s:.2f}"
        return (f"{label:<34} {s.gt:>5} {s.pred:>5} {s.tp:>5} {s.fp:>5} {s.fn:>5} "
                f"{_ratio(s.precision):>6} {_ratio(s.recall):>6} {_ratio(s.f1):>6} "
                f"{s.count_error:>+6d} {dt:>6}")

    lines = [f"tolerance {result.tolerance_s:g} s", head]
    for (kind, target, direction), s in result.groups.items():
        label = kind + (f" {target}" if target else "") + (f" {direction}" if direction else "")
        lines.append(row(label, s))
    if len(result.groups) > 1:
        lines.append("")
        for kind, s in result.by_type.items():
            lines.append(row(f"{kind} (all)", s))
    lines.append(row("TOTAL", result.total))
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from ..errors import ConfigError
    from ..evaluate.events import MAX_TOLERANCE_S, evaluate_events
    from ..io.atomic import atomic_write_text, is_stdout, writing_outputs

    if not (math.isfinite(args.tolerance_s) and 0 <= args.tolerance_s <= MAX_TOLERANCE_S):
        raise ConfigError(f"--tolerance-s must be a number of seconds in "
                          f"[0, {MAX_TOLERANCE_S:.0f}], got {args.tolerance_s}")
    if args.fps is not None and not (math.isfinite(args.fps) and args.fps > 0):
        raise ConfigError(f"--fps must be > 0, got {args.fps}")
    with writing_outputs([args.json] if args.json is not None else [], args.force):
        camera = None
        if args.camera is not None:
            from ..calibrate import load_camera

            camera = load_camera(args.camera)
        if args.scene is None and camera is None:
            from ..io.events import EventsFile, is_events_file, read_events  # no analytics needed

            def load(path: Path, what: str) -> EventsFile:
                if not is_events_file(path) and path.is_file():
                    raise ConfigError(f"{what} {path} is not an events file (its first line is not "
                                      "the motiontrack.events header); give --scene to analyse it "
                                      "as a tracks file")
                return read_events(path)
        else:
            from ..run.evaluate_events import load_events

            def load(path: Path, what: str):
                return load_events(path, args.scene, args.fps, camera, what)

        gt = load(args.gt, "--gt")
        pred = load(args.pred, "--pred")
        result = evaluate_events(gt.events, pred.events, args.tolerance_s)
        print(format_table(result), file=sys.stderr if is_stdout(args.json) else sys.stdout)
        if args.json is not None:
            out = {"gt": str(args.gt), "pred": str(args.pred), **result.to_json()}
            atomic_write_text(args.json, json.dumps(out, indent=1) + "\n")
        return 0
