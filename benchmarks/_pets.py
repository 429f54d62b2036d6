"""The PETS 2009 S2L1 clip and the command line shared by the PETS benchmarks."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from motiontrack.io.mot import read_mot
from motiontrack.types import Annotations


def add_data_argument(ap: argparse.ArgumentParser) -> None:
    """``--data``: the shared data folder (``$MOTIONTRACK_DATA`` or ``../shared/data``)."""
    ap.add_argument("--data", default=os.environ.get("MOTIONTRACK_DATA",
                                                     Path(__file__).resolve().parents[2] / "shared" / "data"))


def pets_video(data: str | Path) -> Path:
    """The PETS clip in ``data``, or exit with a message when it is missing."""
    video = Path(data) / "pets09-s2l1" / "video.avi"
    if not video.is_file():
        sys.exit(f"PETS clip not found: {video} (set MOTIONTRACK_DATA or --data)")
    return video


def pets_args(doc: str | None, repeat: int = 3) -> tuple[argparse.Namespace, Path, Annotations]:
    """Parse ``--data``, ``--frames``, ``--repeat``; return ``(args, video, gt)`` (gt of all
    frames), or exit with a message when the clip is missing."""
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_data_argument(ap)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--repeat", type=int, default=repeat, help="runs per row; the fastest counts")
    args = ap.parse_args()
    video = pets_video(args.data)
    return args, video, read_mot(video.parent / "gt_mot15.txt", kind="gt")
