"""``motiontrack analyze``: scene analytics (lines, zones, dwell, stationary, speed) over an
existing tracks file."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

log = logging.getLogger(__name__)


def register(subparsers) -> None:
    from ._sinks import add_sink_options

    p = subparsers.add_parser(
        "analyze", help="line counts, zone dwell, loitering, stationary and speeding events "
                        "from a tracks file",
        description="Run a scene file's rules over a tracks file in any supported annotation "
                    "format (another tracker's output or ground truth) and write events.jsonl, "
                    "counts.csv, heatmap.png (and heatmap_world.png with --camera) and "
                    "summary.json in the output folder (docs/analytics.md).")
    p.add_argument("tracks", type=Path, help="tracks file (MOTChallenge, CVML, ViPER, CVAT, JSON)")
    p.add_argument("--scene", type=Path, required=True, help="scene file (TOML)")
    p.add_argument("--fps", type=float, default=None,
                   help="frames per second of the tracked video (default: the summary.json of "
                        "the run that wrote the tracks, or a MOTChallenge seqinfo.ini beside them)")
    p.add_argument("--camera", type=Path, default=None,
                   help="camera file (.xml, .yml, .toml): positions in metres, world geometry "
                        "and the scene's rules in metres")
    p.add_argument("--video", default=None,
                   help="the tracked video (file, image folder or glob): heatmap.png is drawn "
                        "over the median of frames sampled from it, at its size (default: on "
                        "black, at the size a seqinfo.ini or summary.json beside the tracks "
                        "states, else the tracks' extent)")
    p.add_argument("-o", "--out", type=Path, required=True, help="output folder")
    p.add_argument("--bin-s", type=float, default=60.0,
                   help="seconds per row of counts.csv (default 60)")
    p.add_argument("--by-class", action="store_true",
                   help="each class's line crossings in counts.csv and a heat map of each class "
                        "(heatmap_person.png ...), from the tracks file's class column")
    p.add_argument("--force", action="store_true", help="replace existing outputs")
    add_sink_options(p, "the name of the tracks file's folder")
    p.set_defaults(func=cmd_analyze)


def cmd_analyze(args: argparse.Namespace) -> int:
    from ..analytics import load_scene
    from ..calibrate import load_camera
    from ..errors import ConfigError
    from ..io.annotations import read_annotations
    from ..run.analyze import analyze_job
    from ..run.folder import RunFolder
    from ..run.folders import source_name
    from ..run.heatmaps import median_background
    from ._common import frame_loop
    from ._sinks import sink_settings, sink_targets, sinks_writer

    targets = sink_targets(args)
    settings = sink_settings(args)
    beside = RunFolder.beside(args.tracks)
    fps = args.fps if args.fps is not None else beside.frame_rate()
    if fps is None:
        raise ConfigError(f"analyze needs the frame rate of {args.tracks.name}: give --fps")
    camera = load_camera(args.camera) if args.camera is not None else None
    scene = load_scene(args.scene, camera)
    tracks = read_annotations(args.tracks)
    background = median_background(args.video) if args.video is not None else None
    size = ((background.shape[1], background.shape[0]) if background is not None
            else beside.frame_size())
    job = analyze_job(tracks, scene, fps, args.out, camera=camera, bin_s=args.bin_s,
                      by_class=args.by_class,
                      force=args.force, source=str(args.tracks), size=size,
                      background=background,
                      sinks=sinks_writer(targets, args.camera_name,
                                         source_name(args.tracks.resolve().parent), settings))
    # the signals every job command takes: SIGINT or SIGTERM keeps the frames analysed so far
    with frame_loop(job.expected_frames()) as loop:
        summary = job.layout(job.run(progress=loop.update, should_stop=loop.stop))
    totals = summary["analytics"]
    n = sum(totals["events"].values())
    lines = ", ".join(f"{k} in {v['in']} out {v['out']}" for k, v in totals["lines"].items())
    print(f"wrote {args.out}: {n} events over {summary['frames']} frames"
          + (f"; {lines}" if lines else ""))
    return 0
