"""``motiontrack sweep``: a parameter study (runs × sequences → table, figures, study.json)."""

from __future__ import annotations

import argparse
import logging
import sys

log = logging.getLogger("motiontrack")


def register(sub: argparse._SubParsersAction) -> None:
    from ._common import add_scoring_option

    p = sub.add_parser(
        "sweep", help="parameter study: run the pipeline over a grid, score it, plot PR curves",
        description="Run the pipeline once per point of the --param grid on SOURCE (or every "
                    "sequence of --sequences) and score the motion regions (framewise pixel/object/"
                    "localized precision and recall, thesis §4.1) and the tracks (HOTA/MOTA/IDF1). "
                    "Writes results.csv (+ .parquet with pyarrow), summary.csv, figures/*.png|svg, "
                    "runs/ and study.json to -o DIR; `--replay DIR` reruns a study exactly.")
    p.add_argument("source", nargs="*", help="video file, image folder or synth:NAME (repeatable)")
    p.add_argument("--gt", action="append", default=[],
                   help="ground truth per SOURCE, in order (optional for synth: sources)")
    p.add_argument("--param", action="append", default=[], metavar="KEY=V1,V2,...|LO:HI:STEP",
                   help="values of one config key: a list, or the inclusive range LO:HI:STEP, e.g. "
                        "motion.knn.dist2_threshold=200:800:200 (repeatable; the grid is the "
                        "product)")
    p.add_argument("--sequences", help="TOML manifest of [[sequence]] tables (name, source, gt, group)")
    p.add_argument("--config", help="base TOML config")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="STAGE.PARAM=VALUE",
                   help="override one base config field (repeatable)")
    p.add_argument("--xi", type=float, default=0.75,
                   help="localization threshold of the localized object metrics (default 0.75)")
    add_scoring_option(p)
    p.add_argument("--save", default="", metavar="STREAMS",
                   help="also write per-run videos: background,difference,motion,annotated")
    p.add_argument("-j", "--jobs", type=int, default=1, help="parallel worker processes (default 1)")
    p.add_argument("--cluster", metavar="URL",
                   help="Dask distributed scheduler, e.g. tcp://host:8786 (pip install 'dask[distributed]')")
    p.add_argument("--replay", metavar="DIR", help="rerun the study recorded in DIR/study.json")
    p.add_argument("--no-figures", action="store_true", help="skip the figures")
    p.add_argument("-o", "--out", required=True, help="output folder")
    p.add_argument("--force", action="store_true", help="overwrite an existing study in -o")
    p.add_argument("--resume", action="store_true",
                   help="continue the study in -o (same settings): runs already done are kept")
    p.set_defaults(func=cmd_sweep)


def cmd_sweep(args) -> int:
    from tqdm import tqdm

    from ..config import load_config
    from ..config_activity import warn_inactive_overrides
    from ..errors import ConfigError, printable
    from ..studies.sweep import TABLE_FILE, load_study, run_sweep, study_from_args, versions
    from ..render.streams import parse_streams
    from ._common import GracefulStop, given, sigterm_as_interrupt

    # options that need no file: refused before anything is read or written
    if args.jobs < 1:
        raise ConfigError(f"-j must be >= 1, got {args.jobs}")
    if args.resume and args.force:
        raise ConfigError("--resume continues a study and --force starts it over: give one of them")
    if args.replay:
        if (args.source or args.param or args.sequences or args.gt or args.config or args.overrides
                or given(args, "scoring")):
            raise ConfigError("--replay takes the study from DIR/study.json; do not give SOURCE, "
                              "--gt, --param, --sequences, --config, --set or --scoring with it")
        study, meta = load_study(args.replay)
        now = versions()
        for k, v in meta.get("versions", {}).items():
            if k != "platform" and now.get(k) != v:
                log.warning("study was run with %s %s, this is %s: numbers may differ",
                            printable(k), printable(v), now.get(k))
    else:
        if not args.param:
            raise ConfigError("give at least one --param stage.name=v1,v2,... (or --replay DIR)")
        cfg = load_config(args.config, args.overrides)
        study = study_from_args(args.source, args.gt, args.param, cfg, args.sequences, args.xi,
                                parse_streams(args.save), scoring=args.scoring)
        warn_inactive_overrides(cfg, args.overrides, domains=dict(study.grid))
    n = study.n_runs
    log.info("%d runs (%d grid points x %d sequences)%s", n, n // len(study.sequences), len(study.sequences),
             f" on {args.cluster}" if args.cluster else (f" with {args.jobs} processes" if args.jobs > 1 else ""))
    # local runs stop after their current frame (the pool's workers are told); the runs of a
    # Dask cluster cannot be told, so there a signal cancels them at once
    signals = sigterm_as_interrupt() if args.cluster else GracefulStop()
    with signals as stop, tqdm(total=n, unit="run", disable=None, file=sys.stderr,
                               dynamic_ncols=True) as bar:
        res = run_sweep(study, args.out, jobs=args.jobs, cluster=args.cluster, progress=bar.update,
                        figures=not args.no_figures, force=args.force, resume=args.resume,
                        should_stop=stop.stop if stop is not None else None)
    _print_best(res.rows, study.keys)
    print(f"scoring   {study.scoring} (HOTA, MOTA and the other tracking metrics)")
    if args.replay:
        from pathlib import Path

        old = Path(args.replay) / TABLE_FILE
        # byte comparison: floats are written with repr, and nan == nan only as text
        same = (old.read_bytes() == (Path(args.out) / TABLE_FILE).read_bytes()) if old.is_file() else None
        if same is not None:
            print(f"replay    {'identical to' if same else 'DIFFERS from'} "
                  f"{printable(args.replay)}/{TABLE_FILE}")
    print(f"outputs   {printable(args.out)}/ (" + ", ".join(p.split('/')[-1] for v in res.outputs.values() for p in v)
          + ")")
    return 0


def _print_best(rows, keys) -> None:
    from ..studies.table import format_summary, summarise_runs

    print(format_summary(summarise_runs(rows, keys), keys), end="")
