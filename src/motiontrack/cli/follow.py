"""``motiontrack follow VIDEO --box x,y,w,h --tracker NAME``: one object from a given box."""

from __future__ import annotations

import argparse
import json
import logging
import time
from pathlib import Path
from typing import Any

log = logging.getLogger("motiontrack")


def parse_params(items: list[str], where: str) -> dict[str, Any]:
    """``["key=value", ...]`` → dict; values parsed as int, float, true/false or left as text."""
    from ..errors import ConfigError

    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ConfigError(f"{where} expects KEY=VALUE, got {item!r}")
        text = text.strip()
        value: Any = text
        if text.lower() in ("true", "false"):
            value = text.lower() == "true"
        else:
            for conv in (int, float):
                try:
                    value = conv(text)
                    break
                except ValueError:
                    pass
        out[key] = value
    return out


def register(sub: argparse._SubParsersAction) -> None:
    from ..tracking.single import SINGLE_TRACKERS

    names = "|".join(SINGLE_TRACKERS.names())
    p = sub.add_parser(
        "follow", help="follow one object from a given box with a single-object tracker",
        description="Follow one object through VIDEO, starting from --box in the first processed "
                    "frame. Writes annotated video, tracks.txt (MOTChallenge, id 1) and "
                    "summary.json to the output folder.")
    p.add_argument("source", help="video file, image folder/glob, camera index, URL or synth:NAME")
    p.add_argument("--box", required=True, metavar="x,y,w,h",
                   help="the object's box in the first processed frame (pixels, top-left + size); "
                        "write --box=-5,10,20,40 when x is negative")
    p.add_argument("--tracker", default="csrt", metavar="NAME", help=f"{names} (default csrt)")
    p.add_argument("--param", dest="params", action="append", default=[], metavar="KEY=VALUE",
                   help="tracker parameter, e.g. --param backbone=nano_backbone.onnx (repeatable)")
    p.add_argument("-o", "--out", default="out", help="output folder (default: out)")
    p.add_argument("--start", type=int, default=0, help="first frame index (0-based)")
    p.add_argument("--max-frames", type=int, default=0, help="process at most this many frames")
    p.add_argument("--no-video", action="store_true", help="no annotated video")
    p.add_argument("--codec", default="vp80", help="video codec: vp80 (default), vp90, mp4v, mjpg")
    p.add_argument("--gt", help="ground truth to score against (synth: sources bring their own)")
    p.add_argument("--gt-id", type=int, help="ground-truth id of the object (default: the one the "
                                             "box overlaps most)")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.set_defaults(func=cmd_follow)


def cmd_follow(args) -> int:
    import numpy as np

    from ..annotate import annotate_frame, draw_label
    from ..errors import ConfigError, RunOutcome, SourceError
    from ..io.atomic import atomic_open, atomic_write_text, check_writable
    from ..io.mot import format_mot_rows
    from ..io.sources import open_source
    from ..io.video import CODECS, VideoSink, extension_for
    from ..tracking.single import create_single_tracker, follow, follow_accuracy, parse_box
    from ..types import Annotations, Track, TrackState
    from ._common import frame_loop, read_gt

    box = parse_box(args.box)
    tracker = create_single_tracker(args.tracker, **parse_params(args.params, "--param"))
    if args.codec not in CODECS:
        raise ConfigError(f"unknown codec {args.codec!r}; valid: {', '.join(CODECS)}")
    if args.start < 0 or args.max_frames < 0:
        raise ConfigError("--start and --max-frames must be >= 0")
    src = open_source(args.source, args.start, args.max_frames)
    gt = read_gt(args.gt) if args.gt else (src.ground_truth() if hasattr(src, "ground_truth") else None)
    out = Path(args.out)
    paths = {"tracks": out / "tracks.txt", "summary": out / "summary.json"}
    if not args.no_video:
        paths["video"] = out / f"annotated{extension_for(args.codec)}"
    check_writable(list(paths.values()), args.force)
    out.mkdir(parents=True, exist_ok=True)

    info = src.info
    log.info("source %s", info.describe())
    video = VideoSink(paths["video"], info.fps or 25.0, args.codec) if "video" in paths else None
    frames_f: list[int] = []
    boxes: list[np.ndarray] = []
    scores: list[float] = []
    history: list[tuple[float, float]] = []
    n = 0
    last_index = args.start - 1
    outcome = RunOutcome()
    t0 = time.perf_counter()
    with atomic_open(paths["tracks"]) as fh, frame_loop(src.expected_frames()) as loop:
        try:
            with outcome:
                for index, image, ok, b, score in follow(src, tracker, box):
                    tracks = ()
                    if ok and b is not None:
                        fh.write(format_mot_rows([index + 1], [1], b.as_array()[None], [score]))
                        frames_f.append(index + 1)
                        boxes.append(b.as_array())
                        scores.append(score)
                        history.append(b.center)
                        del history[:-64]
                        tracks = (Track(id=1, box=b, state=TrackState.CONFIRMED, score=score,
                                        history=tuple(history)),)
                    if video is not None:
                        img = annotate_frame(image, tracks, text=f"frame {index}")
                        label = f"{args.tracker} {score:.2f}" if ok else f"{args.tracker}: lost"
                        draw_label(img, label, (4, 20), (40, 40, 40) if ok else (0, 0, 200))
                        video.write(img)
                    n += 1
                    last_index = index
                    loop.tick()  # SIGINT/SIGTERM: stop here, then finalise the outputs
        finally:
            if video is not None:
                video.close()
            src.close()
    seconds = time.perf_counter() - t0
    status, interrupted = outcome.status, outcome.interrupted
    if status != "complete":
        log.warning("%s after %d frames; writing what was processed", status, n)
    if n == 0 and not interrupted:
        raise SourceError(f"no frames to follow in {args.source} (check --start)")
    summary: dict[str, Any] = {
        "source": info.name, "width": info.width, "height": info.height, "source_fps": info.fps,
        "tracker": args.tracker, "params": parse_params(args.params, "--param"),
        "box": [box.x, box.y, box.w, box.h], "start": args.start, "frames": n,
        "frames_tracked": len(frames_f), "seconds": round(seconds, 3),
        "fps": round(n / seconds, 2) if seconds > 0 else 0.0, "status": status,
        "interrupted": interrupted, "truncated": bool(src.truncated),
        "outputs": {k: str(v) for k, v in paths.items() if v.exists() or k == "summary"},
    }
    if gt is not None:
        pred = Annotations.from_columns(frames_f, np.ones(len(frames_f)),
                                        np.array(boxes).reshape(-1, 4), scores,
                                        meta={"last_frame": last_index + 1})
        summary["accuracy"] = follow_accuracy(gt, pred, args.gt_id)
    atomic_write_text(paths["summary"], json.dumps(summary, indent=2) + "\n")
    outcome.reraise()
    lines = [f"frames    {n} in {seconds:.2f} s ({summary['fps']:.1f} fps), object found in "
             f"{len(frames_f)}"]
    if "accuracy" in summary and summary["accuracy"]["frames"] > 0:
        a = summary["accuracy"]
        lines.append(f"accuracy  gt id {int(a['gt_id'])}: mean IoU {a['mean_iou']:.3f}, "
                     f"IoU>=0.5 in {a['iou50']:.1%} of {int(a['frames'])} frames")
    lines.append(f"outputs   {', '.join(summary['outputs'].values())}")
    print("\n".join(lines))
    return 0
