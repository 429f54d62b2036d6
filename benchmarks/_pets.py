"""The PETS 2009 S2L1 clip and the command line shared by the PETS benchmarks."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from motiontrack.config import PipelineConfig
from motiontrack.evaluate.mot import evaluate_tracking
from motiontrack.io.mot import read_mot
from motiontrack.io.sources import open_source
from motiontrack.pipeline import fill_gap_frames, run
from motiontrack.tracking.gaps import fill_gaps
from motiontrack.types import Annotations, frame_number

#: the scores the PETS accuracy benchmarks print
KEYS = ("HOTA", "MOTA", "IDF1", "recall", "precision", "IDSW")


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


def score_tracks(video: str, cfg: PipelineConfig, gt: Annotations,
                 detections: Annotations | None = None) -> dict[str, float]:
    """:data:`KEYS` of the pipeline's tracks of ``video`` (``cfg``; ``detections`` replace the
    motion stage) against ``gt``, which the caller cuts to the frames the run covers: CLEAR-MOT,
    Identity and HOTA at IoU 0.5, rows with consider = 0 as ignore regions."""
    # the rows `motiontrack track` writes: each frame's tracks and those confirmed in it at their
    # tentative frames (tracker.backfill), then the short gaps filled when the run ends
    rows = [(frame_number(f), t.id, *t.box.as_array()) for r in run(video, cfg, detections=detections)
            for f, t in r.reported]
    a = np.array(rows, float).reshape(-1, 6)
    src = open_source(video)
    fps = src.info.fps
    src.close()
    pred = fill_gaps(Annotations.from_columns(a[:, 0], a[:, 1], a[:, 2:6]),
                     fill_gap_frames(cfg, fps, detections is not None))
    res = evaluate_tracking(gt, pred, ignore_zero_marked=True)
    return {k: res[k] for k in KEYS}
