"""``motiontrack evaluate-masks``: CDnet 2014 motion-mask metrics for a folder of masks."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from ..errors import ConfigError
from ._common import checked_max_pixels, max_pixels_option


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "evaluate-masks",
        help="score binary motion masks against CDnet ground truth",
        description="Compare predicted motion masks (0/255 images, frame number in the file name, "
                    "e.g. bin000470.png) with CDnet 2014 ground truth (gt%06d.png) inside the "
                    "spatial and temporal ROI. Shadow pixels count as negatives, unknown and "
                    "outside-ROI pixels are ignored (CDnet rules).",
    )
    p.add_argument("--gt", required=True, type=Path,
                   help="ground-truth folder (groundtruth/ or the CDnet video folder holding it)")
    p.add_argument("--pred", required=True, type=Path, help="folder of predicted masks")
    p.add_argument("--roi", type=Path, default=None,
                   help="spatial ROI image (default: ROI.bmp next to the groundtruth folder)")
    p.add_argument("--temporal-roi", type=Path, default=None,
                   help="temporalROI.txt (default: the one next to the groundtruth folder)")
    p.add_argument("--frames", default=None, metavar="A:B",
                   help="only frames A..B (inclusive), intersected with the temporal ROI")
    p.add_argument("--pred-prefix", default=None,
                   help="only prediction files whose name starts with this (e.g. bin)")
    p.add_argument("--json", type=Path, default=None,
                   help="write counts and metrics as JSON (- for standard output; the table then "
                        "goes to standard error)")
    p.add_argument("--force", action="store_true", help="overwrite an existing --json file")
    max_pixels_option(p)
    p.set_defaults(func=run)


def _frames(text: str | None) -> tuple[int, int] | None:
    if text is None:
        return None
    try:
        a, b = text.split(":")
        lo, hi = int(a), int(b)
    except ValueError:
        raise ConfigError(f"--frames must be A:B with integers, got {text!r}") from None
    if not 0 <= lo <= hi:
        raise ConfigError(f"--frames needs 0 <= A <= B, got {text!r}")
    return lo, hi


def format_table(result) -> str:
    """The readable table printed by the command."""
    c = result.counts
    lines = [f"frames        {c.frames}",
             f"TP            {c.tp}", f"FP            {c.fp}", f"FN            {c.fn}",
             f"TN            {c.tn}", f"shadow FP     {c.shadow_errors} of {c.shadow}", ""]
    labels = {"recall": "Recall", "specificity": "Specificity", "fpr": "FPR", "fnr": "FNR",
              "pwc": "PWC (%)", "precision": "Precision", "f_measure": "F-measure",
              "fpr_shadow": "FPR-S"}
    for key, label in labels.items():
        v = result.metrics[key]
        lines.append(f"{label:<13} {'n/a' if math.isnan(v) else f'{v:.6f}'}")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from ..evaluate.masks import evaluate_mask_folders
    from ..io.atomic import atomic_write_text, is_stdout, writing_outputs

    with writing_outputs([args.json] if args.json is not None else [], args.force):
        result = evaluate_mask_folders(args.gt, args.pred, roi=args.roi,
                                       temporal_roi=args.temporal_roi, frames=_frames(args.frames),
                                       pred_prefix=args.pred_prefix,
                                       max_pixels=checked_max_pixels(args))
        print(format_table(result), file=sys.stderr if is_stdout(args.json) else sys.stdout)
        if args.json is not None:
            flat = {k: (None if isinstance(v, float) and math.isnan(v) else v)
                    for k, v in result.as_dict().items()}
            atomic_write_text(args.json, json.dumps(flat, indent=1) + "\n")
        return 0
