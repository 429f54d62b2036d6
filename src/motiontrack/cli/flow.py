"""``motiontrack flow SOURCE --mode sparse|dense``: follow motion with optical flow.

* ``sparse``: Shi–Tomasi features in moving regions, forward–backward checked pyramidal
  Lucas–Kanade, points grouped into objects → ``tracks.txt`` (MOTChallenge), annotated video with
  feature trails, ``summary.json``, ``config.toml``.
* ``dense``: Farnebäck flow → HSV flow video (hue = direction, brightness = magnitude), optionally
  the flow-magnitude motion mask video (``--mask-video``), ``summary.json``.
"""

from __future__ import annotations

import argparse
import logging
from dataclasses import fields

log = logging.getLogger("motiontrack")


def register(sub: argparse._SubParsersAction) -> None:
    from ..config_flags import add_flag
    from ._common import CodecOption, out_help
    from ._common import add_scoring_option

    p = sub.add_parser(
        "flow", help="follow motion with sparse (Lucas-Kanade) or dense (Farneback) optical flow",
        description="Sparse mode tracks feature points inside moving regions and groups them into "
                    "objects (tracks.txt + annotated video with feature trails); dense mode writes "
                    "an HSV flow video (hue = direction, brightness = magnitude) and optionally "
                    "the flow-magnitude mask video.")
    p.add_argument("source", help="video file, image folder/glob, camera index, URL or synth:NAME")
    p.add_argument("--mode", choices=("sparse", "dense"), default="sparse",
                   help="sparse (default) or dense")
    p.add_argument("-o", "--out", help=out_help("flow"))
    p.add_argument("--config", help="TOML config file (motion, cleanup, regions, farneback settings)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="STAGE.PARAM=VALUE",
                   help="override one config field, e.g. --set motion.farneback.threshold=1.0")
    p.add_argument("--param", dest="params", action="append", default=[], metavar="KEY=VALUE",
                   help="sparse-flow parameter (see docs/flow_and_single.md), e.g. "
                        "--param fb_threshold=0.5 (repeatable)")
    p.add_argument("--max-magnitude", type=float, default=None,
                   help="dense: flow magnitude (px/frame) shown at full brightness (default: each "
                        "frame's maximum)")
    add_flag(p, "--start")
    add_flag(p, "--max-frames")
    add_flag(p, "--fps")
    add_flag(p, "--no-video", help="sparse: no annotated video")
    add_flag(p, "--mask-video")
    add_flag(p, "--codec", action=CodecOption)
    p.add_argument("--gt", help="sparse: ground truth to score against (synth: sources bring "
                                "their own)")
    add_scoring_option(p)
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
    from ..config_activity import warn_inactive_overrides
    from ._common import run_overrides

    overrides = run_overrides(args, ("start", "max_frames", "fps", "codec", "no_video",
                                     "mask_video"))
    cfg = load_config(args.config, overrides)
    if args.mode == "dense":  # the Farneback detector, whatever motion.method says
        warn_inactive_overrides(cfg, args.overrides, points=[{"motion.method": "farneback"}],
                                reads=("dense flow", ("source", "motion.farneback", "output")))
    else:
        warn_inactive_overrides(cfg, args.overrides, reads=("sparse flow", (
            "source", "preprocess", "motion", "cleanup", "regions", "output")))
    return cfg


def cmd_flow(args) -> int:
    from ..errors import ConfigError
    from ..run import dense_flow_job, sparse_flow_job
    from ._common import frame_loop, given, output_folder, read_gt

    cfg = _config(args)
    if args.max_magnitude is not None and not args.max_magnitude > 0:
        raise ConfigError(f"--max-magnitude must be > 0, got {args.max_magnitude}")
    if args.mode == "sparse":
        gt = read_gt(args.gt) if args.gt else None
        job = sparse_flow_job(args.source, cfg, output_folder(args, "flow"),
                              sparse_params(args.params),
                              force=args.force, gt=gt, scoring=args.scoring)
    else:
        if args.params:
            raise ConfigError("--param applies to --mode sparse; dense flow takes "
                              "--set motion.farneback.NAME=VALUE")
        if args.gt:
            # dense flow makes no tracks, so there is nothing to score against ground truth
            raise ConfigError("--gt applies to --mode sparse (its tracks are scored); dense flow "
                              "makes no tracks to score")
        if given(args, "scoring"):
            raise ConfigError("--scoring applies to --mode sparse with --gt; dense flow makes no "
                              "tracks to score")
        job = dense_flow_job(args.source, cfg, output_folder(args, "flow"),
                             max_magnitude=args.max_magnitude,
                             force=args.force)
    log.info("source %s", job.info.describe())
    with frame_loop(job.expected_frames()) as loop:
        s = job.run(progress=loop.update, should_stop=loop.stop)
    print("\n".join(_report(s)))
    return 0


def _report(s) -> list[str]:
    from ._common import accuracy_line

    lines = [f"frames    {s.frames} in {s.seconds:.2f} s ({s.fps:.1f} fps)",
             f"status    {s.status}" + (" (input truncated)" if s.truncated else "")]
    if s.extra["mode"] == "sparse":
        lines.append(f"tracks    {s.tracks}")
        if s.accuracy:
            lines.append(accuracy_line(s.accuracy, ("HOTA", "MOTA", "IDF1")))
    else:
        e = s.extra
        lines.append(f"flow      mean {e['mean_magnitude']:.3f} px/frame, max "
                     f"{e['peak_magnitude']:.2f}, moving {e['moving_fraction']:.1%} of pixels")
    lines.append(f"outputs   {', '.join(s.outputs.values())}")
    return lines
