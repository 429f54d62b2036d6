"""``motiontrack world``: fill MOTChallenge columns 8-9 with ground positions in metres."""

from __future__ import annotations

import argparse
import logging
from dataclasses import replace
from pathlib import Path

log = logging.getLogger(__name__)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "world", help="add world coordinates (metres) of each box's bottom centre",
        description="Read a MOTChallenge tracks file, back-project each box's bottom centre onto "
                    "the ground plane Z = 0 and write world_x, world_y (metres) in columns 8-9 "
                    "(column 10 = 0). Foot points above the horizon get -1,-1,-1.")
    p.add_argument("tracks", type=Path, help="MOTChallenge CSV (results or gt)")
    p.add_argument("--camera", type=Path, required=True, help="camera file (.xml, .yml, .toml)")
    p.add_argument("-o", "--output", type=Path, required=True,
                   help="output CSV (- for standard output)")
    p.add_argument("--force", action="store_true", help="overwrite an existing output")
    p.set_defaults(func=cmd_world)


def cmd_world(args: argparse.Namespace) -> int:
    import numpy as np

    from ..calibrate.camera import load_camera
    from ..calibrate.measure import world_positions
    from ..errors import check_output_path
    from ..io.atomic import is_stdout, writing_outputs
    from ..io.mot import read_mot, write_mot

    check_output_path(args.output, "-o")
    camera = load_camera(args.camera)
    ann = read_mot(args.tracks)
    with writing_outputs([args.output], args.force):
        xy = world_positions(ann.boxes, camera)
        ok = np.all(np.isfinite(xy), axis=1)
        world = np.full((len(ann), 3), -1.0)
        world[ok, :2] = xy[ok]
        world[ok, 2] = 0.0
        if (~ok).any():
            log.warning("%d of %d foot points are above the horizon: world set to -1",
                        int((~ok).sum()), len(ann))
        out = replace(ann, world=world)
        write_mot(out, args.output, kind=str(ann.meta.get("kind", "results")))
        if not is_stdout(args.output):
            print(f"wrote {args.output} ({len(ann)} boxes)")
        return 0
