"""``motiontrack gt-stats``: recommended region-size limits from the ground truth (thesis eqs. 4.27–4.30)."""

from __future__ import annotations

import argparse
import json
import sys


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "gt-stats", help="ground-truth box statistics → recommended MIN/MAX_REGION_SIZE",
        description="Mean and standard deviation of the ground-truth box areas as fractions of the "
                    "image area, the recommended MIN_REGION_SIZE = mu - sigma and MAX_REGION_SIZE = "
                    "mu + sigma (thesis eqs. 4.27-4.30) and height-to-width limits.")
    p.add_argument("gt", nargs="+", help="ground-truth file(s), any supported format (pooled)")
    p.add_argument("--image-size", required=True, metavar="WxH", help="frame size, e.g. 768x576")
    p.add_argument("--sample-std", action="store_true", help="use the sample std (N-1) instead of N")
    p.add_argument("--json", metavar="PATH",
                   help="also write the numbers as JSON (- for standard output; the table then "
                        "goes to standard error)")
    p.add_argument("--force", action="store_true", help="overwrite an existing --json file")
    p.set_defaults(func=cmd_gt_stats)


def cmd_gt_stats(args) -> int:
    from ..errors import check_output_path
    from ..evaluate.gtstats import gt_statistics, parse_image_size
    from ..io.atomic import atomic_write_text, check_writable, is_stdout

    if args.json:
        from pathlib import Path

        check_output_path(args.json, "--json")
        check_writable([Path(args.json)], args.force)
    from ._common import read_gt

    size = parse_image_size(args.image_size)
    stats = gt_statistics([read_gt(g) for g in args.gt], size, ddof=1 if args.sample_std else 0)
    width = max(len(k) for k in stats)
    for k, v in stats.items():
        if k == "recommended_overrides":
            v = " ".join(f"--set {s}" for s in v)
        elif isinstance(v, float):
            v = f"{v:.6g}"
        print(f"{k:<{width}}  {v}", file=sys.stderr if is_stdout(args.json) else sys.stdout)
    if args.json:
        atomic_write_text(args.json, json.dumps(stats, indent=2) + "\n")
    return 0
