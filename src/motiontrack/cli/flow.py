"""``motiontrack flow SOURCE --mode sparse|dense``: follow motion with optical flow.

* ``sparse``: Shi–Tomasi features in moving regions, forward–backward checked pyramidal
  Lucas–Kanade, points grouped into objects → ``tracks.txt`` (MOTChallenge), annotated video with
  feature trails, ``summary.json``, ``config.toml``.
* ``dense``: Farnebäck flow → HSV flow video (hue = direction, brightness = magnitude), optionally
  the flow-magnitude motion mask video (``--mask-video``), ``summary.json``.
"""

from __future__ import annotations

import argparse
import json
import logging
import time
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

log = logging.getLogger("motiontrack")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "flow", help="follow motion with sparse (Lucas-Kanade) or dense (Farneback) optical flow",
        description="Sparse mode tracks feature points inside moving regions and groups them into "
                    "objects (tracks.txt + annotated video with feature trails); dense mode writes "
                    "an HSV flow video (hue = direction, brightness = magnitude) and optionally "
                    "the flow-magnitude mask video.")
    p.add_argument("source", help="video file, image folder/glob, camera index, URL or synth:NAME")
    p.add_argument("--mode", choices=("sparse", "dense"), default="sparse",
                   help="sparse (default) or dense")
    p.add_argument("-o", "--out", default="out", help="output folder (default: out)")
    p.add_argument("--config", help="TOML config file (motion, cleanup, regions, farneback settings)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="STAGE.PARAM=VALUE",
                   help="override one config field, e.g. --set motion.farneback.threshold=1.0")
    p.add_argument("--param", dest="params", action="append", default=[], metavar="KEY=VALUE",
                   help="sparse-flow parameter (see docs/flow_and_single.md), e.g. "
                        "--param fb_threshold=0.5 (repeatable)")
    p.add_argument("--max-magnitude", type=float, default=None,
                   help="dense: flow magnitude (px/frame) shown at full brightness (default: each "
                        "frame's maximum)")
    p.add_argument("--start", type=int, help="first frame index (0-based)")
    p.add_argument("--max-frames", type=int, help="process at most this many frames")
    p.add_argument("--no-video", action="store_true", help="sparse: no annotated video")
    p.add_argument("--mask-video", action="store_true", help="also write the motion mask video")
    p.add_argument("--codec", help="video codec: vp80 (default, WebM), vp90, mp4v, mjpg, xvid")
    p.add_argument("--gt", help="sparse: ground truth to score against (synth: sources bring "
                                "their own)")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.set_defaults(func=cmd_flow)


def sparse_params(items: list[str]):
    """``--param`` values → :class:`~motiontrack.tracking.flow.SparseFlowParams`."""
    from ..errors import ConfigError
    from ..tracking.flow import SparseFlowParams
    from .follow import parse_params

    given = parse_params(items, "--param")
    valid = {f.name: f.type for f in fields(SparseFlowParams)}
    unknown = sorted(set(given) - set(valid))
    if unknown:
        raise ConfigError(f"unknown sparse-flow parameter(s) {', '.join(unknown)}; valid: "
                          f"{', '.join(valid)}")
    for k, v in given.items():
        default = getattr(SparseFlowParams(), k)
        if isinstance(default, int) and not (isinstance(v, int) and not isinstance(v, bool)):
            raise ConfigError(f"sparse-flow parameter {k} must be an integer, got {v!r}")
        if isinstance(v, bool) or (isinstance(default, float) and not isinstance(v, (int, float))):
            raise ConfigError(f"sparse-flow parameter {k} must be a number, got {v!r}")
        given[k] = type(default)(v)
    return SparseFlowParams(**given)


def _config(args):
    from ..config import load_config
    from ._common import run_overrides

    return load_config(args.config, run_overrides(args))


def cmd_flow(args) -> int:
    from ..errors import ConfigError

    cfg = _config(args)
    if args.max_magnitude is not None and not args.max_magnitude > 0:
        raise ConfigError(f"--max-magnitude must be > 0, got {args.max_magnitude}")
    params = sparse_params(args.params) if args.mode == "sparse" else None
    if args.mode == "dense" and args.params:
        raise ConfigError("--param applies to --mode sparse; dense flow takes "
                          "--set motion.farneback.NAME=VALUE")
    from ..pipeline import open_configured_source

    src = open_configured_source(args.source, cfg)
    try:
        if args.mode == "sparse":
            return _sparse(args, cfg, params, src)
        return _dense(args, cfg, src)
    finally:
        src.close()


def _finish(paths: dict[str, Path], summary: dict[str, Any], outcome) -> None:
    """Write the summary, then let an interrupt or a failed source surface (RunOutcome)."""
    from ..io.atomic import atomic_write_text

    summary["outputs"] = {k: str(v) for k, v in paths.items() if v.exists() or k == "summary"}
    atomic_write_text(paths["summary"], json.dumps(summary, indent=2) + "\n")
    outcome.reraise()


def _sparse(args, cfg, params, src) -> int:
    import numpy as np

    from ..annotate import annotate_frame
    from ..config import save_config
    from ..errors import RunOutcome
    from ..io.atomic import atomic_open, check_writable
    from ..io.mot import format_mot_rows
    from ..io.video import VideoSink, extension_for
    from ..tracking.flow import SparseFlowTracker, draw_feature_trails
    from ..types import Annotations
    from ._common import accuracy_line, frame_loop, read_gt

    out = Path(args.out)
    ext = extension_for(cfg.output.codec)
    paths = {"tracks": out / "tracks.txt", "summary": out / "summary.json",
             "config": out / "config.toml"}
    if not args.no_video:
        paths["video"] = out / f"annotated{ext}"
    if args.mask_video:
        paths["mask_video"] = out / f"mask{ext}"
    check_writable(list(paths.values()), args.force)
    gt = read_gt(args.gt) if args.gt else (src.ground_truth() if hasattr(src, "ground_truth") else None)
    info = src.info
    log.info("source %s", info.describe())
    out.mkdir(parents=True, exist_ok=True)
    save_config(cfg, paths["config"])
    tracker = SparseFlowTracker((info.width, info.height), params, cfg.motion, cfg.cleanup,
                                cfg.regions, cfg.preprocess)
    fps = info.fps or 25.0
    video = VideoSink(paths["video"], fps, cfg.output.codec) if "video" in paths else None
    mask_video = VideoSink(paths["mask_video"], fps, cfg.output.codec) if "mask_video" in paths else None
    rows_f: list[int] = []
    rows_id: list[int] = []
    rows_box: list[np.ndarray] = []
    n = 0
    outcome = RunOutcome()
    t0 = time.perf_counter()
    with atomic_open(paths["tracks"]) as fh, frame_loop(src.expected_frames()) as loop:
        try:
            with outcome:
                for frame in src:
                    tracks = tracker.update(frame.image)
                    if tracks:
                        boxes = np.array([t.box.as_array() for t in tracks])
                        f = [frame.index + 1] * len(tracks)
                        ids = [t.id for t in tracks]
                        fh.write(format_mot_rows(f, ids, boxes, [t.score for t in tracks]))
                        rows_f += f
                        rows_id += ids
                        rows_box.append(boxes)
                    if video is not None:
                        img = annotate_frame(frame.image, tracks, (), tracker.last_mask,
                                             cfg.output.trail, cfg.output.mask_inset,
                                             text=f"frame {frame.index}")
                        shown = {t.id for t in tracks}
                        draw_feature_trails(img, [tr for tr in tracker.trails() if tr[0] in shown])
                        video.write(img)
                    if mask_video is not None and tracker.last_mask is not None:
                        mask_video.write(tracker.last_mask)
                    n += 1
                    loop.tick()  # SIGINT/SIGTERM: stop here, then finalise the outputs
        finally:
            for sink in (video, mask_video):
                if sink is not None:
                    sink.close()
    seconds = time.perf_counter() - t0
    status, interrupted = outcome.status, outcome.interrupted
    if status != "complete":
        log.warning("%s after %d frames; writing what was processed", status, n)
    summary: dict[str, Any] = {
        "source": info.name, "width": info.width, "height": info.height, "source_fps": info.fps,
        "mode": "sparse", "params": asdict(params), "frames": n, "seconds": round(seconds, 3),
        "fps": round(n / seconds, 2) if seconds > 0 else 0.0, "tracks": len(set(rows_id)),
        "status": status, "interrupted": interrupted, "truncated": bool(src.truncated),
    }
    if gt is not None and n:
        from ..pipeline import score_run

        pred = Annotations.from_columns(
            rows_f, rows_id, np.concatenate(rows_box) if rows_box else np.zeros((0, 4)))
        summary["accuracy"] = score_run(gt, pred, n, src)
    _finish(paths, summary, outcome)
    lines = [f"frames    {n} in {seconds:.2f} s ({summary['fps']:.1f} fps)",
             f"tracks    {summary['tracks']}"]
    if "accuracy" in summary:
        lines.append(accuracy_line(summary["accuracy"], ("HOTA", "MOTA", "IDF1")))
    lines.append(f"outputs   {', '.join(summary['outputs'].values())}")
    print("\n".join(lines))
    return 0


def _dense(args, cfg, src) -> int:
    from ..errors import RunOutcome
    from ..io.atomic import check_writable
    from ..io.video import extension_for
    from ..motion.dense_flow import write_flow_videos
    from ._common import frame_loop

    out = Path(args.out)
    ext = extension_for(cfg.output.codec)
    paths = {"flow_video": out / f"flow{ext}", "summary": out / "summary.json"}
    if args.mask_video:
        paths["mask_video"] = out / f"mask{ext}"
    check_writable(list(paths.values()), args.force)
    info = src.info
    log.info("source %s", info.describe())
    out.mkdir(parents=True, exist_ok=True)
    stats = None
    t0 = time.perf_counter()
    with frame_loop(src.expected_frames()) as loop, RunOutcome() as outcome:
        stats = write_flow_videos(src, paths["flow_video"], info.fps or 25.0,
                                  mask_path=paths.get("mask_video"), codec=cfg.output.codec,
                                  params=cfg.motion.farneback,
                                  max_magnitude=args.max_magnitude, progress=loop.update,
                                  should_stop=loop.stop)
        if stats.stopped:
            raise KeyboardInterrupt
    seconds = time.perf_counter() - t0
    status, interrupted = outcome.status, outcome.interrupted
    if status != "complete":
        log.warning("%s; the videos hold what was processed", status)
    summary: dict[str, Any] = {
        "source": info.name, "width": info.width, "height": info.height, "source_fps": info.fps,
        "mode": "dense", "farneback": asdict(cfg.motion.farneback),
        "max_magnitude": args.max_magnitude, "seconds": round(seconds, 3),
        "status": status, "interrupted": interrupted, "truncated": bool(src.truncated),
    }
    if stats is not None:
        summary.update(asdict(stats))
        summary["fps"] = round(stats.frames / seconds, 2) if seconds > 0 else 0.0
    _finish(paths, summary, outcome)
    if stats is not None:
        print(f"frames    {stats.frames} in {seconds:.2f} s\n"
              f"flow      mean {stats.mean_magnitude:.3f} px/frame, max "
              f"{stats.max_magnitude:.2f}, moving {stats.moving_fraction:.1%} of pixels\n"
              f"outputs   {', '.join(summary['outputs'].values())}")
    return 0
