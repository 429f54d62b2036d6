"""``motiontrack shape train``: learn a point-distribution model of people outlines.

From a synthetic scene (exact masks of isolated figures)::

    motiontrack shape train synth:walker -o model.npz
    motiontrack shape train synth:walker,runner --seeds 0-5 -o model.npz

or from any video with ground truth (motion masks of isolated people inside their gt boxes)::

    motiontrack shape train video.avi --gt gt.txt -o model.npz

``motiontrack shape info model.npz`` prints a model's size and provenance.
"""

from __future__ import annotations

import argparse
import logging

from ..errors import ConfigError

log = logging.getLogger(__name__)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("shape", help="active shape model of people: train, info",
                       description="Point-distribution model (PCA of aligned B-spline outlines) for "
                                   "the active shape tracker; see docs/people.md.")
    ssub = p.add_subparsers(dest="shape_command", metavar="COMMAND", help="what to do with a shape model")
    ssub.required = True

    t = ssub.add_parser("train", help="learn a shape model from synthetic figures or video + gt",
                        description="Learn a shape model. SOURCE is synth:NAME[,NAME...] (exact masks "
                                    "of the synthetic figures) or any video source with --gt.")
    t.add_argument("source", help="synth:NAME[,NAME...] or a video file / image folder")
    t.add_argument("--gt", help="ground truth for a video source (any supported format)")
    t.add_argument("-o", "--out", required=True, help="output model (.npz)")
    t.add_argument("--control-points", type=int, default=32, help="spline control points (default 32)")
    t.add_argument("--xi", type=float, default=0.95,
                   help="fraction of the variance the kept modes explain (default 0.95)")
    t.add_argument("--dmax", type=float, default=3.0, help="Mahalanobis bound (default 3)")
    t.add_argument("--every", type=int, default=3, help="use every N-th frame (default 3)")
    t.add_argument("--seeds", default="0-5", help="synthetic seeds: A-B or a,b,c (default 0-5)")
    t.add_argument("--min-height", type=float, default=40.0,
                   help="skip people shorter than this (px, default 40)")
    t.add_argument("--max-frames", type=int, default=0, help="video: stop after N frames (0 = all)")
    t.add_argument("--force", action="store_true", help="overwrite an existing output")
    t.set_defaults(func=cmd_train)

    i = ssub.add_parser("info", help="print a shape model's size and provenance")
    i.add_argument("model", help="model .npz")
    i.set_defaults(func=cmd_info)


def _seeds(text: str) -> list[int]:
    try:
        if "-" in text:
            a, b = text.split("-", 1)
            out = list(range(int(a), int(b) + 1))
        else:
            out = [int(s) for s in text.split(",") if s.strip()]
    except ValueError:
        raise ConfigError(f"--seeds must be A-B or a,b,c with integers, got {text!r}") from None
    if not out or min(out) < 0:
        raise ConfigError(f"--seeds must name non-negative seeds, got {text!r}")
    return out


def cmd_train(args) -> int:
    from pathlib import Path

    from ..people.training import save_model, train_shape_model

    if args.control_points < 4:
        raise ConfigError(f"--control-points must be >= 4, got {args.control_points}")
    if not 0 < args.xi <= 1:
        raise ConfigError(f"--xi must be in (0, 1], got {args.xi}")
    if args.dmax <= 0 or args.every < 1:
        raise ConfigError("--dmax must be > 0 and --every >= 1")
    out = Path(args.out)
    if out.exists() and not args.force:
        raise ConfigError(f"{out} exists; use --force to overwrite")
    shapes, meta = (_synth_outlines(args) if args.source.startswith("synth:")
                    else _video_outlines(args))
    if len(shapes) < 2:
        raise ConfigError(f"found {len(shapes)} usable outline(s) of isolated people; need at least 2 "
                          "(try --every 1, a lower --min-height or more frames)")
    model = train_shape_model(shapes, xi=args.xi, dmax=args.dmax, meta=meta)
    save_model(model, out)
    print(f"{out}: {model.n_control} control points, {model.n_modes} modes explaining "
          f"{model.meta['explained']:.3f} of the variance, from {len(shapes)} outlines")
    return 0


def _synth_outlines(args) -> tuple[list, dict]:
    """Training outlines and provenance from ``synth:NAME[,NAME...]`` with ``--seeds``."""
    from ..people.training import outlines_from_synth
    from ..synth import SCENES

    if args.gt:
        raise ConfigError("--gt is not used with synth: sources (their ground truth is exact)")
    names = [n.strip() for n in args.source[len("synth:"):].split(",") if n.strip()]
    bad = [n for n in names if n not in SCENES]
    if not names or bad:
        raise ConfigError(f"unknown synthetic scene(s) {bad or names}; valid: {', '.join(SCENES)}")
    seeds = _seeds(args.seeds)
    shapes = []
    for n in names:
        shapes.extend(outlines_from_synth(n, seeds=seeds, n_control=args.control_points,
                                          every=args.every, min_height=args.min_height))
    return shapes, {"source": args.source, "seeds": seeds, "every": args.every}


def _video_outlines(args) -> tuple[list, dict]:
    """Training outlines and provenance from a video source with ``--gt``."""
    from ..people.training import outlines_from_video
    from ._common import read_gt

    if not args.gt:
        raise ConfigError("a video source needs --gt (ground-truth boxes of the people)")
    gt = read_gt(args.gt)
    shapes = list(outlines_from_video(args.source, gt, n_control=args.control_points,
                                      every=args.every, min_height=args.min_height,
                                      max_frames=args.max_frames))
    return shapes, {"source": str(args.source), "gt": str(args.gt), "every": args.every}


def cmd_info(args) -> int:
    import json

    from ..people.shape_model import ShapeModel

    m = ShapeModel.load(args.model)
    print(f"{args.model}: {m.n_control} control points, {m.n_modes} modes, xi={m.xi}, dmax={m.dmax}")
    print("variances: " + " ".join(f"{v:.4g}" for v in m.variances))
    print("meta: " + json.dumps(m.meta, sort_keys=True))
    return 0
