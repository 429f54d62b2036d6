"""``motiontrack tune``: Optuna search for the best configuration (optional extra)."""

from __future__ import annotations

import argparse
import functools
import logging
import sys

log = logging.getLogger("motiontrack")


def register(sub: argparse._SubParsersAction) -> None:
    from ._common import add_scoring_option

    p = sub.add_parser(
        "tune", help="search parameters that maximise a metric (needs optuna)",
        description="Search the --param space with Optuna (seeded TPE) for the best mean --metric on "
                    "the training sequences, score the best configuration on the validation "
                    "sequences and write it as best_config.toml (use with `motiontrack track "
                    "--config`).")
    p.add_argument("--train", action="append", default=[], metavar="SOURCE[=GT]|MANIFEST.toml",
                   help="training sequence: a source (with =GT unless synth:) or a manifest (repeatable)")
    p.add_argument("--val", action="append", default=[], metavar="SOURCE[=GT]|MANIFEST.toml",
                   help="validation sequence(s), never used by the search (repeatable)")
    p.add_argument("--param", action="append", default=[],
                   metavar="KEY=V1,V2,...|LO:HI:STEP|LO:HI[:log]",
                   help="values of one config key, searched: a list (choices), the range LO:HI:STEP "
                        "(the values of the same sweep --param), or a continuous range LO:HI, "
                        "uniform or on a log scale, e.g. motion.knn.dist2_threshold=100:1000:log "
                        "(repeatable)")
    p.add_argument("--metric", default="det_object_f1",
                   help="table column to optimise (default det_object_f1; e.g. det_pixel_f1, HOTA)")
    p.add_argument("--minimize", action="store_true", help="minimise the metric instead")
    p.add_argument("--trials", type=int, default=20, help="number of trials (default 20)")
    p.add_argument("--seed", type=int, default=0, help="sampler seed (default 0)")
    p.add_argument("--config", help="base TOML config")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="STAGE.PARAM=VALUE",
                   help="override one base config field, e.g. --set motion.method=knn (repeatable)")
    p.add_argument("--xi", type=float, default=0.75, help="localization threshold (default 0.75)")
    add_scoring_option(p)
    p.add_argument("-j", "--jobs", type=int, default=1, help="processes per trial (over sequences)")
    p.add_argument("-o", "--out", required=True, help="output folder")
    p.add_argument("--force", action="store_true", help="overwrite an earlier tuning in --out")
    p.set_defaults(func=cmd_tune)


def _sequences(items, what):
    from ..errors import ConfigError
    from ..io.manifest import SequenceSpec, absolute_path, default_sequence_name, read_manifest

    out = []
    for it in items:
        if it.endswith(".toml"):
            out.extend(read_manifest(it))
            continue
        src, gt = (it.rsplit("=", 1) if "=" in it and not it.startswith("synth:") else (it, None))
        if gt == "":
            raise ConfigError(f"--{'train' if what == 'training' else 'val'} {it!r}: no ground "
                              "truth after '='")
        source = src if src.startswith("synth:") else absolute_path(src)
        out.append(SequenceSpec(name=default_sequence_name(src), source=source,
                                gt=absolute_path(gt)))
    names = [s.name for s in out]
    if len(set(names)) != len(names):
        raise ConfigError(f"{what} sequence names must be unique, got {names}")
    return out


#: the files of a tuning folder (``--force`` removes them all before the search starts)
TUNE_OUTPUTS = ("best_config.toml", "tune.json", "trials.csv", "trials.parquet", "validation.csv",
                "validation.parquet")


def _owning_out(cmd):
    """``cmd(args)`` run as the only owner of the folder ``args.out``: a second tuning into it
    is refused at once."""

    @functools.wraps(cmd)
    def owned(args) -> int:
        from ..io.atomic import OutputLock

        _check_options(args)  # before the lock creates the folder: a refusal writes nothing
        with OutputLock(args.out):
            return cmd(args)

    return owned


def _check_options(args) -> None:
    """Refuse options that need no file, and an -o that cannot be a folder, before anything is
    written or searched (rather than when the search's results are written)."""
    from ..errors import ConfigError, check_output_path

    if args.jobs < 1:
        raise ConfigError(f"-j must be >= 1, got {args.jobs}")
    if args.trials < 1:
        raise ConfigError(f"--trials must be >= 1, got {args.trials}")
    check_output_path(args.out, "-o", folder=True)


@_owning_out
def cmd_tune(args) -> int:
    from tqdm import tqdm

    from ..config import load_config
    from ..config_activity import warn_inactive_overrides
    from ..errors import ConfigError, printable
    from ..studies.sweep import TRACKING_KEYS
    from ..studies.tune import parse_space, require_optuna, tune, write_tune_outputs
    from ._common import sigterm_as_interrupt

    from pathlib import Path

    from ..io.atomic import check_writable, remove_leftover_temps, remove_outputs

    check_writable([Path(args.out) / "best_config.toml", Path(args.out) / "tune.json"], args.force)
    optuna = require_optuna()
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    if not args.train:
        raise ConfigError("give at least one --train sequence")
    cfg = load_config(args.config, args.overrides)
    space = [parse_space(p) for p in args.param]
    warn_inactive_overrides(cfg, args.overrides, domains={p.key: p.domain for p in space})
    train, val = _sequences(args.train, "training"), _sequences(args.val, "validation")
    overlap = {s.source for s in train} & {s.source for s in val}
    if overlap:
        log.warning("validation sequence(s) also used for training: %s", ", ".join(sorted(overlap)))
    outputs = [Path(args.out) / n for n in TUNE_OUTPUTS]
    if args.force:  # the old tuning goes before the new one appears: never a mixture of both
        remove_outputs(outputs)
    remove_leftover_temps(outputs)
    # SIGTERM stops the search as Ctrl-C does: the finished trials are written
    with sigterm_as_interrupt(), tqdm(total=args.trials, unit="trial", disable=None,
                                      file=sys.stderr, dynamic_ncols=True) as bar:
        res = tune(train, val, space, cfg, metric=args.metric,
                   direction="minimize" if args.minimize else "maximize", n_trials=args.trials,
                   seed=args.seed, xi=args.xi, jobs=args.jobs, progress=bar.update,
                   scoring=args.scoring)
    paths = write_tune_outputs(res, args.out)
    if res.interrupted:
        log.warning("interrupted after %d of %d trials: the best of those is written, not "
                    "validated", len(res.trials), args.trials)
    print("best      " + "  ".join(f"{k}={v:.6g}" if isinstance(v, float) else printable(f"{k}={v}")
                                   for k, v in res.best_params.items()))
    print(f"train     {args.metric} {res.train_score:.4f} (mean over {len(train)} sequence(s))")
    if res.validation_score is not None:
        print(f"validate  {args.metric} {res.validation_score:.4f} (mean over {len(val)} sequence(s))")
    if args.metric in TRACKING_KEYS:
        print(f"scoring   {res.scoring}")
    print(f"outputs   {printable(', '.join(paths.values()))}")
    return 130 if res.interrupted else 0
