"""``motiontrack gt-stats``: the ground truth's box statistics, the thesis' size model (eqs.
4.27–4.30) and region-filter limits that keep the ground truth's people (``--write-config``)."""

from __future__ import annotations

import argparse
import json
import sys

from ..errors import ConfigError, InputError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "gt-stats", help="ground-truth box statistics → region-filter limits that keep its people",
        description="Statistics of the ground-truth boxes; the thesis' size model (MIN_REGION_SIZE "
                    "= mu - sigma, MAX_REGION_SIZE = mu + sigma, eqs. 4.27-4.30; reported, not "
                    "recommended: it drops about a third of the people by construction); and the "
                    "recommended regions.min_size/max_size/min_hw_ratio/max_hw_ratio: percentiles "
                    "of the people's boxes and of the groups they form, widened for segmentation "
                    "noise, as --set strings or a config file for `track --config`.")
    p.add_argument("gt", nargs="+", help="ground-truth file(s) or glob patterns "
                                         "('gt/*.txt'), any supported format (pooled)")
    p.add_argument("--image-size", required=True, metavar="WxH", help="frame size, e.g. 768x576")
    p.add_argument("--sample-std", action="store_true", help="use the sample std (N-1) instead of N")
    p.add_argument("--percentile", type=float, action=_PercentileOption, metavar="Q")
    p.add_argument("--write-config", metavar="FILE",
                   help="write the recommended limits as a TOML config for `track --config FILE`")
    p.add_argument("--json", metavar="PATH",
                   help="also write the numbers as JSON (- for standard output; the table then "
                        "goes to standard error)")
    p.add_argument("--force", action="store_true",
                   help="overwrite an existing --json or --write-config file")
    p.set_defaults(func=cmd_gt_stats)


class _PercentileOption(argparse.Action):
    """``--percentile Q``, whose default (named in its help) is
    :data:`~motiontrack.evaluate.gtstats.DEFAULT_PERCENTILE`, read only when ``gt-stats`` parses
    its arguments or shows its help: that module loads NumPy, which no other command's start
    needs."""

    def __init__(self, option_strings, dest, default=None, **kwargs) -> None:
        kwargs.pop("help", None)
        super().__init__(option_strings, dest, **kwargs)

    @property
    def default(self) -> float:
        from ..evaluate.gtstats import DEFAULT_PERCENTILE

        return DEFAULT_PERCENTILE

    @default.setter
    def default(self, value) -> None:   # argparse sets it; the value is the library's
        pass

    @property
    def help(self) -> str:
        return ("the recommendation's low percentile; the high one is 100 - Q "
                f"(default {self.default:g})")

    @help.setter
    def help(self, value) -> None:
        pass

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        setattr(namespace, self.dest, values)


def cmd_gt_stats(args) -> int:
    from ..errors import check_output_path
    from ..evaluate.gtstats import check_percentile, gt_statistics, parse_image_size
    from ..io.atomic import atomic_write_text, is_stdout, writing_outputs

    from pathlib import Path

    outputs = [(args.json, "--json"), (args.write_config, "--write-config")]
    for path, flag in outputs:
        if path:
            check_output_path(path, flag)
    if args.write_config and is_stdout(args.write_config) and is_stdout(args.json):
        raise ConfigError("--json and --write-config cannot both be standard output (-)")
    with writing_outputs([Path(p) for p, _ in outputs if p], args.force):
        from ._common import read_gt

        size = parse_image_size(args.image_size)
        check_percentile(args.percentile)
        from ..io.paths import expand_paths

        files = expand_paths(args.gt, "ground-truth files")
        stats = gt_statistics([read_gt(str(g)) for g in files], size,
                              ddof=1 if args.sample_std else 0, percentile=args.percentile)
        if args.write_config and not stats["recommended_overrides"]:
            raise InputError("--write-config: the ground truth has no boxes to count (none, or all "
                             "marked consider = 0), so there are no limits to recommend")
        table = sys.stderr if is_stdout(args.json) or is_stdout(args.write_config) else sys.stdout
        width = max(len(k) for k in stats)
        for k, v in stats.items():
            if k.endswith("_overrides"):
                v = " ".join(f"--set {s}" for s in v)
            elif isinstance(v, float):
                v = f"{v:.6g}"
            print(f"{k:<{width}}  {v}", file=table)
        if args.json:
            atomic_write_text(args.json, json.dumps(stats, indent=2) + "\n")
        if args.write_config:
            atomic_write_text(args.write_config, recommendation_toml(stats))
            if not is_stdout(args.write_config):
                print(f"wrote {args.write_config}: use it with `motiontrack track SOURCE --config "
                      f"{args.write_config}`", file=table)
        return 0


def recommendation_toml(stats: dict) -> str:
    """The recommended limits of :func:`gt_statistics` as a config file (the ``[regions]``
    section only; ``track --config`` keeps every other key at its default)."""
    import tomli_w

    section = {s.split("=", 1)[0].split(".", 1)[1]: float(s.split("=", 1)[1])
               for s in stats["recommended_overrides"]}
    q = stats["percentile_low"]
    head = (f"# Region-filter limits that keep the ground truth's people (motiontrack gt-stats):\n"
            f"# percentiles {q:g} / {100 - q:g} of the people's boxes and of the groups they form,\n"
            f"# widened for segmentation noise. Not the thesis' mu +- sigma model.\n")
    return head + tomli_w.dumps({"regions": section})
