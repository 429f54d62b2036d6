"""``motiontrack evaluate``: score tracker output against ground truth.

CLEAR-MOT / Identity / HOTA (identical to TrackEval, :mod:`motiontrack.evaluate.mot`) and the
ViPER-style framewise metrics (:mod:`motiontrack.evaluate.framewise`). ``--pred`` may be one file
or a folder holding one result file per tracker; a folder gives one comparison table.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import logging
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import ConfigError, InputError
from ..io.atomic import atomic_write_text, is_stdout, writing_outputs
from ..evaluate.scoring import DEFAULT_SCORING, SCORING_SUMMARY, ignores_zero_marked
from ._common import add_scoring_option, frame_range

if TYPE_CHECKING:  # NumPy and the data model load when the command runs, not with every command
    from ..evaluate.score import ScoredFrames
    from ..types import Annotations

log = logging.getLogger(__name__)

TRACKING = ("clear", "identity", "hota")
ALL_METRICS = TRACKING + ("framewise",)
#: columns of the printed table, in order (those present are shown)
TABLE_KEYS = ("HOTA", "DetA", "AssA", "LocA", "MOTA", "MOTP", "IDF1", "IDP", "IDR", "IDSW", "Frag",
              "MT", "PT", "ML", "TP", "FP", "FN", "pixel_precision", "pixel_recall",
              "object_area_precision", "object_area_recall", "fragmentation",
              "localized_object_precision", "localized_object_recall")
#: columns that are counts, printed as integers; every other column is a ratio, printed in percent
COUNT_KEYS = frozenset({"IDSW", "Frag", "MT", "PT", "ML", "TP", "FP", "FN"})
_SHORT = {"pixel_precision": "pixP", "pixel_recall": "pixR", "object_area_precision": "objAP",
          "object_area_recall": "objAR", "fragmentation": "frag",
          "localized_object_precision": "locP", "localized_object_recall": "locR"}
_RESULT_SUFFIXES = {".txt", ".csv", ".xml", ".xgtf", ".json"}


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "evaluate",
        help="score tracker output against ground truth (CLEAR-MOT, Identity, HOTA, framewise)",
        description="Score tracker output against ground truth. CLEAR-MOT, Identity and HOTA follow "
                    "TrackEval and the MOTChallenge conventions (IoU >= 0.5; tracker boxes on "
                    "distractor classes are removed, zero-marked gt rows are dropped; --scoring "
                    "ignore-regions drops the tracker boxes on them too); framewise metrics follow "
                    "ViPER-PE. The table prints ratios in percent and counts as integers.",
    )
    p.add_argument("--gt", help="ground-truth file (MOT CSV, ViPER, CVML, CVAT, JSON)")
    p.add_argument("--pred", action="append",
                   help="tracker result file, or a folder with one result file per tracker; "
                        "repeatable: one row per result file, named by the file, or by its folder "
                        "when file names repeat (e.g. many tracks.txt)")
    p.add_argument("--gt-folder", type=Path, metavar="SPLIT",
                   help="instead of --gt/--pred, a MOTChallenge benchmark (as TrackEval's "
                        "run_mot_challenge.py): SPLIT/<seq>/gt/gt.txt and SPLIT/<seq>/seqinfo.ini "
                        "(seqLength); every sequence scored and all of them combined as TrackEval "
                        "combines them (COMBINED)")
    p.add_argument("--trackers-folder", type=Path, metavar="TRACKERS",
                   help="with --gt-folder: TRACKERS/<tracker>/data/<seq>.txt, one sub-folder per "
                        "tracker, each needing a file for every sequence")
    p.add_argument("--seqmap", type=Path, metavar="FILE",
                   help="with --gt-folder: the sequences to evaluate, a TrackEval seqmap file "
                        "(header line, then one name per line; default every sequence folder)")
    p.add_argument("--frames", type=frame_range, metavar="A:B",
                   help="evaluate only frames A..B (inclusive, 1-based; within those the "
                        "ground truth covers)")
    p.add_argument("--score-outside-gt", action="store_true",
                   help="also score the predicted frames outside the ground truth's (its first "
                        "to last frame, or 1 to the seqLength of a seqinfo.ini beside it), whose "
                        "boxes are then false positives; by default they are left out and a line "
                        "says how many")
    p.add_argument("--metrics", default=None,
                   help="comma-separated subset of clear,identity,hota,framewise "
                        "(default: all that are available)")
    p.add_argument("--xi", type=float, default=0.75,
                   help="localization threshold of the framewise metrics (default 0.75)")
    add_scoring_option(p)
    p.add_argument("--json", type=Path, metavar="OUT.json",
                   help="write the metrics as JSON (one flat object; a folder --pred gives "
                        "{tracker: object}); - writes them to standard output and the table to "
                        "standard error")
    p.add_argument("--per-frame", type=Path, metavar="OUT.csv",
                   help="write per-frame counts (and framewise metrics) as CSV (- for standard "
                        "output)")
    p.add_argument("--force", action="store_true", help="overwrite existing --json/--per-frame files")
    p.set_defaults(func=run)


def _parse_metrics(text: str | None) -> tuple[str, ...]:
    if text is None:
        return TRACKING + ("framewise",)
    ms = tuple(dict.fromkeys(m.strip().lower() for m in text.split(",") if m.strip()))
    bad = [m for m in ms if m not in ALL_METRICS]
    if bad or not ms:
        raise ConfigError(f"unknown metric {bad[0] if bad else text!r}; choose from "
                          f"{', '.join(ALL_METRICS)}")
    return ms


def _read(path: Path, role: str) -> Annotations:
    """Read an annotation file; an empty *result* file is a valid "found nothing"."""
    if not path.is_file():
        raise InputError(f"{role} file not found: {path}")
    if role == "result" and not path.read_bytes().strip():
        from ..types import Annotations

        return Annotations.empty()
    from ..io.annotations import read_annotations, read_ground_truth

    if role == "ground-truth":   # with the length of a seqinfo.ini beside it
        return read_ground_truth(path)
    return read_annotations(path, mot_kind="results")


def _pred_files(pred: Path) -> list[tuple[str, Path]]:
    if pred.is_dir():
        files = sorted(p for p in pred.iterdir()
                       if p.is_file() and p.suffix.lower() in _RESULT_SUFFIXES
                       and not p.name.startswith("."))
        if not files:
            raise InputError(f"no result files (.txt/.csv/.xml/.xgtf/.json) in folder {pred}")
        return [(p.stem, p) for p in files]
    if not pred.exists():
        raise InputError(f"result file not found: {pred}")
    return [(pred.stem, pred)]


def _named(items: list[tuple[str, Path]]) -> list[tuple[str, Path]]:
    """Unique row names: a file's stem, or as many of its folders as it takes to tell it from
    the others with the same stem (``run1/tracks``, ``run2/tracks``); the path when nothing
    else does."""
    out = []
    for name, path in items:
        same = [p for n, p in items if n == name and p != path]
        depth = 0
        while same and depth < len(path.parts):
            depth += 1
            label = "/".join([*path.parent.parts[len(path.parent.parts) - depth:], path.stem])
            same = [p for p in same
                    if "/".join([*p.parent.parts[len(p.parent.parts) - depth:], p.stem]) == label]
            name = label
        out.append((name if not same else str(path), path))
    return out


def evaluate_one(gt: Annotations, pred: Annotations, metrics: tuple[str, ...], xi: float,
                 frames: tuple[int, int | None] | None = None,
                 scoring: str = DEFAULT_SCORING, outside: bool = False
                 ) -> tuple[dict, list[dict], ScoredFrames]:
    """Flat metrics, per-frame rows and the scored frames for one tracker (the command's work,
    without I/O).

    The frames scored are ``frames`` (``--frames``) within those the ground truth covers
    (:func:`~motiontrack.evaluate.score.scored_frames`; ``outside``: all of ``frames``, the
    predictions beyond the ground truth then false positives). ``scoring`` names how
    zero-marked gt rows count (:data:`~motiontrack.evaluate.scoring.SCORING`); with tracking
    metrics the flat dict names it under ``"scoring"``."""
    from ..evaluate.clear import clear_metrics
    from ..evaluate.hota import hota_metrics
    from ..evaluate.identity import identity_metrics
    from ..evaluate.mot import flatten
    from ..evaluate.score import scored_frames
    from ..evaluate.sequence import preprocess

    gt, pred, window = scored_frames(gt, pred, frames, outside=outside)
    if window.empty:
        c = window.covered
        raise InputError(f"--frames {frames[0]}:{frames[1] or ''} holds none of the ground "
                         f"truth's frames {c[0]}–{c[1]} (--score-outside-gt scores the "
                         f"predictions there as false positives)")
    flat: dict = {}
    rows: dict[int, dict] = {}
    tracking = tuple(m for m in metrics if m in TRACKING)
    if tracking:
        data = preprocess(gt, pred, ignore_zero_marked=ignores_zero_marked(scoring))
        res = {}
        if "clear" in tracking:
            per: list[dict] = []
            res["clear"] = clear_metrics(data, per_frame=per)
            for r in per:
                rows.setdefault(r["frame"], {"frame": r["frame"]}).update(r)
        if "identity" in tracking:
            res["identity"] = identity_metrics(data)
        if "hota" in tracking:
            res["hota"] = hota_metrics(data)
        flat.update(flatten(res))
        flat["scoring"] = scoring
    if "framewise" in metrics:
        from ..evaluate.framewise import evaluate_framewise

        rng = None
        if window.first is not None:
            last = max([int(a.frames.max()) for a in (gt, pred) if len(a)] or [window.first])
            rng = (window.first, window.last if window.last is not None else last)
        overall, per_frame = evaluate_framewise(gt, pred, xi, frames=rng)
        flat.update(overall)
        for r in per_frame:
            f = int(r["frame"])
            rows.setdefault(f, {"frame": f}).update({k: v for k, v in r.items() if k != "frame"})
    return flat, [rows[f] for f in sorted(rows)], window


def _fmt(key: str, v) -> str:
    """One cell: a count as an integer, a ratio in percent with two decimals, whatever its value
    (MOTA has no lower bound: -250.00 is MOTA -2.5), so a column has one format."""
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    if key in COUNT_KEYS:
        return str(int(round(float(v))))
    return f"{100 * float(v):.2f}"


def format_table(results: dict[str, dict], label: str = "tracker") -> str:
    """A plain-text table: one row per tracker (``label`` heads the column of row names), one
    column per metric (counts as integers, ratios in percent), and a last line naming the
    scoring convention of the tracking metrics."""
    keys = [k for k in TABLE_KEYS if any(k in r for r in results.values())]
    head = [label] + [_SHORT.get(k, k) for k in keys]
    body = [[name] + [_fmt(k, r.get(k)) for k in keys] for name, r in results.items()]
    widths = [max(len(row[i]) for row in [head] + body) for i in range(len(head))]
    lines = ["  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(row, widths)))
             for row in [head] + body]
    lines = lines[:1] + ["-" * len(lines[0])] + lines[1:]
    scorings = list(dict.fromkeys(r["scoring"] for r in results.values() if "scoring" in r))
    if scorings:
        lines.append("ratios in percent; " + "; ".join(f"scoring {s}: {SCORING_SUMMARY[s]}"
                                                      for s in scorings))
    return "\n".join(lines) + "\n"


def _jsonable(v):
    import numpy as np

    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return None if math.isnan(v) else v
    return v


def run(args: argparse.Namespace) -> int:
    if args.gt_folder is not None or args.trackers_folder is not None:
        return run_benchmark(args)
    if args.seqmap is not None:
        raise ConfigError("--seqmap selects sequences of --gt-folder; give --gt-folder and "
                          "--trackers-folder with it")
    if args.gt is None or not args.pred:
        raise ConfigError("give --gt and --pred (one sequence), or --gt-folder and "
                          "--trackers-folder (a MOTChallenge benchmark)")
    metrics = _parse_metrics(args.metrics)
    outputs = [p for p in (args.json, args.per_frame) if p is not None]
    if sum(map(is_stdout, outputs)) > 1:
        raise ConfigError("--json and --per-frame cannot both be - (standard output)")
    if not 0.0 <= args.xi <= 1.0:
        raise ConfigError(f"--xi must be in [0, 1], got {args.xi}")
    # the lock of each output's folder (a run's folder, often) from the check to the write
    with writing_outputs(outputs, args.force):
        return _evaluate_pred(args, metrics, outputs)


def _evaluate_pred(args: argparse.Namespace, metrics: tuple[str, ...],
                   outputs: list[Path]) -> int:
    """``--gt`` against every ``--pred`` file: the table, ``--json`` and ``--per-frame``."""
    gt = _read(Path(args.gt), "ground-truth")
    if len(gt) == 0:
        raise InputError(f"ground-truth file has no annotations: {args.gt}")
    results: dict[str, dict] = {}
    per_rows: list[dict] = []
    files = _named([f for pred in args.pred for f in _pred_files(Path(pred))])
    if len({p.resolve() for _, p in files}) < len(files):
        raise ConfigError("the same result file is given more than once in --pred")
    for name, path in files:
        pred = _read(path, "result")
        log.info("evaluating %s (%d boxes) against %s (%d boxes)", path, len(pred), args.gt, len(gt))
        try:
            flat, rows, window = evaluate_one(gt, pred, metrics, args.xi, args.frames,
                                              args.scoring, args.score_outside_gt)
        except InputError as exc:  # name the file: a folder may hold many
            raise InputError(f"{path}: {exc}") from None
        if window.note():
            log.info("%s: %s", name, window.note())
        results[name] = flat
        # the per-frame counts depend on the convention too: each row names it
        tag = {"scoring": flat["scoring"]} if "scoring" in flat else {}
        per_rows += [{"tracker": name, **tag, **r} for r in rows]
    # the table goes to standard error when standard output carries a file
    (sys.stderr if any(map(is_stdout, outputs)) else sys.stdout).write(format_table(results))
    if args.json:
        obj = ({k: _jsonable(v) for k, v in next(iter(results.values())).items()}
               if len(args.pred) == 1 and not Path(args.pred[0]).is_dir()
               else {n: {k: _jsonable(v) for k, v in r.items()} for n, r in results.items()})
        atomic_write_text(args.json, json.dumps(obj, indent=2, sort_keys=True) + "\n")
        log.info("wrote %s", args.json)
    if args.per_frame:
        cols = list(dict.fromkeys(k for r in per_rows for k in r))
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=cols, restval="", lineterminator="\n")
        w.writeheader()
        for r in per_rows:
            w.writerow({k: _jsonable(v) for k, v in r.items()})
        atomic_write_text(args.per_frame, buf.getvalue())
        log.info("wrote %s", args.per_frame)
    return 0


def run_benchmark(args: argparse.Namespace) -> int:
    """``--gt-folder SPLIT --trackers-folder TRACKERS``: every tracker on every sequence of the
    split, and the sequences combined, as TrackEval's ``run_mot_challenge.py``."""
    if args.gt is not None or args.pred:
        raise ConfigError("--gt-folder/--trackers-folder evaluate a benchmark folder; they cannot "
                          "be combined with --gt/--pred (one sequence)")
    if args.gt_folder is None or args.trackers_folder is None:
        raise ConfigError("a benchmark needs both --gt-folder and --trackers-folder")
    if args.frames is not None or args.per_frame is not None:
        raise ConfigError("--frames and --per-frame apply to --gt/--pred, not to a benchmark "
                          "folder (sequences are scored whole, as TrackEval does)")
    if args.score_outside_gt:
        raise ConfigError("--score-outside-gt applies to --gt/--pred; a benchmark folder is "
                          "scored over its seqinfo.ini lengths, as TrackEval does")
    metrics = _parse_metrics(args.metrics) if args.metrics is not None else TRACKING
    if "framewise" in metrics:
        raise ConfigError("framewise metrics are not combined over sequences; with --gt-folder "
                          "choose from clear,identity,hota")
    outputs = [args.json] if args.json is not None else []
    with writing_outputs(outputs, args.force):
        return _evaluate_benchmark(args, metrics)


def _evaluate_benchmark(args: argparse.Namespace, metrics: tuple[str, ...]) -> int:
    """Every tracker of ``--trackers-folder`` on every sequence: the tables and ``--json``."""
    from ..evaluate.benchmark import COMBINED, evaluate_tracker, flatten_benchmark
    from ..io.mot import read_mot
    from ..io.mot_layout import split_sequences, tracker_file, tracker_names

    seqs = split_sequences(args.gt_folder, args.seqmap)
    trackers = tracker_names(args.trackers_folder)
    # every file is found before any is read: a missing one fails at once, as in TrackEval
    files = {t: {s.name: tracker_file(args.trackers_folder, t, s.name) for s in seqs}
             for t in trackers}
    gt = {s.name: read_mot(s.gt_path, kind="gt") for s in seqs}
    lengths = {s.name: s.length for s in seqs}
    zero = ignores_zero_marked(args.scoring)
    results: dict[str, dict[str, dict]] = {}
    for t in trackers:
        log.debug("evaluating %s on %d sequences", t, len(seqs))
        pred = {seq: read_mot(path, kind="results") for seq, path in files[t].items()}
        try:
            res = evaluate_tracker(gt, lengths, pred, metrics, ignore_zero_marked=zero)
        except InputError as exc:  # name the tracker: the folder holds many
            raise InputError(f"tracker {t}: {exc}") from None
        results[t] = {seq: {**flat, "scoring": args.scoring}
                      for seq, flat in flatten_benchmark(res).items()}
    out = sys.stderr if args.json is not None and is_stdout(args.json) else sys.stdout
    for i, (t, rows) in enumerate(results.items()):
        out.write(("\n" if i else "") + f"{t} ({len(rows) - 1} sequences and {COMBINED})\n")
        out.write(format_table(rows, label="sequence"))
    if args.json:
        # sequences in evaluation order, COMBINED last; metric keys sorted as for --gt/--pred
        obj = {t: {seq: {k: _jsonable(flat[k]) for k in sorted(flat)} for seq, flat in rows.items()}
               for t, rows in results.items()}
        atomic_write_text(args.json, json.dumps(obj, indent=2) + "\n")
        log.info("wrote %s", args.json)
    return 0
