"""``motiontrack overlay``: ground truth and several runs on the video, one colour each, with a legend."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    from ._common import FPS_HELP

    p = sub.add_parser(
        "overlay", help="draw ground truth and several runs on the video (distinct colours, legend)",
        description="Render SOURCE with the ground truth (green) and each --pred run in its own "
                    "colour, as a video and/or PNG stills.")
    p.add_argument("source", help="video file, image folder or synth:NAME")
    p.add_argument("--gt", help="ground truth (any supported format; default: a synth: scene's own)")
    p.add_argument("--pred", action="append", default=[], metavar="[NAME=]FILE",
                   help="a run's tracks (any supported format; a sweep run folder's tracks.txt); "
                        "repeatable; NAME is the legend text (default: the file's folder name); "
                        "without NAME= a glob pattern ('study/runs/*/*/tracks.txt') gives one "
                        "run per file")
    p.add_argument("-o", "--out", help="output video (e.g. overlay.webm)")
    p.add_argument("--frames", metavar="A:B", help="1-based inclusive frame range")
    p.add_argument("--fps", type=float, help=FPS_HELP)
    p.add_argument("--force", action="store_true", help="overwrite an existing output video")
    p.add_argument("--png-frames", default="", metavar="F1,F2",
                   help="also write these 1-based frames as PNG (frame_%%06d.png next to -o)")
    p.add_argument("--png-dir", help="folder for the PNG stills")
    p.add_argument("--codec", default=None, help="video codec (default from the -o extension: vp80 "
                                                 "for .webm, h264 for .mp4 when this installation "
                                                 "encodes it, else mp4v, mjpg for .avi; "
                                                 "`motiontrack list` shows the codecs)")
    p.set_defaults(func=cmd_overlay)


def _pred(item: str):
    from pathlib import Path

    from ..io.annotations import read_annotations

    if "=" in item and not Path(item).exists():
        name, path = item.split("=", 1)
    else:
        path = item
        p = Path(item)
        name = f"{p.parent.parent.name}/{p.parent.name}" if p.parent.parent.name.startswith("r") \
            and p.parent.parent.name[1:].isdigit() else (p.parent.name or p.stem)
    return name, read_annotations(path, mot_kind="results")


def cmd_overlay(args) -> int:
    from pathlib import Path

    from ..errors import ConfigError
    from ..run import overlay_job
    from ._common import frame_loop, frame_range, read_gt

    from ..io.paths import expand_paths

    # a --pred without NAME= may be a glob pattern: one run per file it matches
    runs = [_pred(str(f)) for item in args.pred
            for f in ([item] if "=" in item and not Path(item).exists()
                      else expand_paths([item], "track files"))]
    gt = read_gt(args.gt) if args.gt else None
    try:
        pngs = [int(x) for x in args.png_frames.split(",") if x.strip()]
    except ValueError:
        raise ConfigError(f"--png-frames expects comma-separated frame numbers, got {args.png_frames!r}") from None
    codec = args.codec
    if codec is None and args.out:
        from ..io.video import encodable_codecs

        mp4 = "h264" if "h264" in encodable_codecs() else "mp4v"   # h264 plays in browsers
        codec = {".mp4": mp4, ".avi": "mjpg"}.get(Path(args.out).suffix.lower(), "vp80")
    first, last = frame_range(args.frames) if args.frames else (1, None)
    job = overlay_job(args.source, args.out, runs, gt, first=first, last=last, png_frames=pngs,
                      png_dir=args.png_dir, codec=codec or "vp80", force=args.force,
                      fps=args.fps or 0.0)
    with frame_loop(job.expected_frames()) as loop:
        s = job.run(progress=loop.update, should_stop=loop.stop)
    print(f"frames    {s.frames}")
    print(f"outputs   {', '.join(s.outputs.values())}")
    return 0
