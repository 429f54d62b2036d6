"""The PETS 2009 S2L1 clip and the command line shared by the PETS benchmarks."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from motiontrack.io.mot import read_mot
from motiontrack.types import Annotations


def pets_args(doc: str | None, repeat: int = 3) -> tuple[argparse.Namespace, Path, Annotations]:
    """Parse ``--data``, ``--frames``, ``--repeat``; return ``(args, video, gt)`` (gt of all
    frames), or exit with a message when the clip is missing."""
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", default=os.environ.get("MOTIONTRACK_DATA",
                                                     Path(__file__).resolve().parents[2] / "shared" / "data"))
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--repeat", type=int, default=repeat, help="runs per row; the fastest counts")
    args = ap.parse_args()
    video = Path(args.data) / "pets09-s2l1" / "video.avi"
    if not video.is_file():
        sys.exit(f"PETS clip not found: {video} (set MOTIONTRACK_DATA or --data)")
    return args, video, read_mot(video.parent / "gt_mot15.txt", kind="gt")
