"""``motiontrack follow VIDEO --box x,y,w,h --tracker NAME``: one object from a given box."""

from __future__ import annotations

import argparse
import logging
import math
from typing import Any

log = logging.getLogger("motiontrack")


#: bounds of an integer tracker parameter: what OpenCV's ``int`` parameters hold
_INT_MIN, _INT_MAX = -(2**31), 2**31 - 1


def parse_params(items: list[str], where: str) -> dict[str, Any]:
    """``["key=value", ...]`` → dict; values parsed as int, float, true/false or left as text.

    Numbers are checked here, before any tracker sees them: integers must fit a C ``int`` and
    floats must be finite (``nan`` and ``inf`` parse as floats but mean nothing to a tracker).
    """
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
        if isinstance(value, int) and not isinstance(value, bool) and not (
                _INT_MIN <= value <= _INT_MAX):
            raise ConfigError(f"{where} {key}: integer out of range [{_INT_MIN}, {_INT_MAX}]")
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"{where} {key}: expected a finite number, got {value}")
        out[key] = value
    return out


def check_model_files(params: dict[str, Any], where: str) -> list[str]:
    """Load every parameter that names an existing file as an OpenCV DNN model first, so that a
    file that is not a model (corrupt, truncated, another format) is a clear error here rather
    than an OpenCV exception once the video is open. Returns the keys that name model files."""
    from pathlib import Path

    import cv2

    from ..errors import ConfigError, printable

    models = []
    for key, value in params.items():
        if not isinstance(value, str) or not value or not Path(value).is_file():
            continue
        try:
            cv2.dnn.readNet(value)
        except cv2.error:
            raise ConfigError(f"{where} {key}={printable(value)}: not a model OpenCV can read "
                              "(expected an ONNX file from the OpenCV model zoo)") from None
        models.append(key)
    return models


def register(sub: argparse._SubParsersAction) -> None:
    from ..config_flags import add_flag
    from ._common import CodecOption, out_help

    p = sub.add_parser(
        "follow", help="follow one object from a given box with a single-object tracker",
        description="Follow one object through VIDEO, starting from --box in the first processed "
                    "frame. Writes annotated video, tracks.txt (MOTChallenge, id 1) and "
                    "summary.json to the output folder.")
    p.add_argument("source", help="video file, image folder/glob, camera index, URL or synth:NAME")
    p.add_argument("--box", required=True, metavar="x,y,w,h",
                   help="the object's box in the first processed frame (pixels, top-left + size); "
                        "write --box=-5,10,20,40 when x is negative")
    # no names listed here: they come from the tracker module (OpenCV, SciPy), which is
    # imported when follow runs, not whenever any command starts
    p.add_argument("--tracker", default="csrt", metavar="NAME",
                   help="single-object tracker (default csrt; `motiontrack list` names those "
                        "this installation has)")
    p.add_argument("--param", dest="params", action="append", default=[], metavar="KEY=VALUE",
                   help="tracker parameter, e.g. --param backbone=nano_backbone.onnx (repeatable)")
    p.add_argument("-o", "--out", help=out_help("follow"))
    add_flag(p, "--start", default=0)
    add_flag(p, "--max-frames", default=0)
    add_flag(p, "--fps")
    p.add_argument("--no-video", action="store_true", help="no annotated video")
    add_flag(p, "--codec", default="vp80", action=CodecOption)
    p.add_argument("--gt", help="ground truth to score against (synth: sources bring their own)")
    p.add_argument("--gt-id", type=int, help="ground-truth id of the object (default: the one the "
                                             "box overlaps most)")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.set_defaults(func=cmd_follow)


def cmd_follow(args) -> int:
    import cv2

    from ..config import load_config
    from ..config_flags import flag_overrides
    from ..errors import ConfigError, SourceError, check_output_path, opencv_reason
    from ..io.video import check_codec
    from ..run import follow_job
    from ..tracking.single import create_single_tracker, parse_box
    from ._common import frame_loop, output_folder, read_gt

    box = parse_box(args.box)
    params = parse_params(args.params, "--param")
    tracker = create_single_tracker(args.tracker, **params)
    models = check_model_files(params, "--param")
    out = output_folder(args, "follow")
    check_output_path(out, "-o", folder=True)
    check_codec(args.codec)
    if args.start < 0 or args.max_frames < 0:
        raise ConfigError("--start and --max-frames must be >= 0")
    # --no-video of follow leaves out its own video, not a config key
    cfg = load_config(None, flag_overrides(args, ("start", "max_frames", "fps", "codec")))
    gt = read_gt(args.gt) if args.gt else None
    job = follow_job(args.source, cfg, out, tracker, box, args.tracker, params=params,
                     video=not args.no_video, force=args.force, gt=gt, gt_id=args.gt_id)
    log.info("source %s", job.info.describe())
    try:
        with frame_loop(job.expected_frames()) as loop:
            s = job.run(progress=loop.update, should_stop=loop.stop)
    except (cv2.error, ConfigError) as exc:
        # a tracker that OpenCV refuses to start (tracking.single) is a ConfigError from a
        # cv2.error; with model files of the user's, the models are the likely cause
        cause = exc if isinstance(exc, cv2.error) else exc.__cause__
        if not models or not isinstance(cause, cv2.error):
            raise  # no model file of the user's: an OpenCV failure elsewhere is a bug
        given = ", ".join(f"--param {k}" for k in models)
        raise ConfigError(f"the {args.tracker} tracker cannot run with the model file(s) given "
                          f"({given}): OpenCV says {opencv_reason(cause)}") from None
    if s.frames == 0:
        raise SourceError(f"no frames to follow in {args.source} (check --start)")
    lines = [f"frames    {s.frames} in {s.seconds:.2f} s ({s.fps:.1f} fps), object found in "
             f"{s.extra['frames_tracked']}"]
    a = s.accuracy
    if a and a["frames"] > 0:
        lines.append(f"accuracy  gt id {int(a['gt_id'])}: mean IoU {a['mean_iou']:.3f}, "
                     f"IoU>=0.5 in {a['iou50']:.1%} of {int(a['frames'])} frames")
    lines.append(f"outputs   {', '.join(s.outputs.values())}")
    print("\n".join(lines))
    return 0
