"""``motiontrack batch SOURCES... -o RESULTS``: one track run per video on a Dask cluster."""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

log = logging.getLogger("motiontrack")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "batch", help="track many videos on a local or remote Dask cluster, with an index of results",
        description="Run `track` on every video of SOURCES (files, folders, globs such as "
                    "'videos/**/*.mp4', manifest .toml files, synth: scenes) into RESULTS/<name>/, "
                    "and write RESULTS/index.csv with one row per video (docs/batch.md).")
    p.add_argument("sources", nargs="+", metavar="SOURCES",
                   help="video files, folders, quoted globs ('videos/**/*.mp4'), manifest .toml "
                        "files of [[sequence]] tables, synth: scenes")
    p.add_argument("-o", "--out", required=True, metavar="RESULTS", help="results folder")
    p.add_argument("--preset", help="shipped settings to start from (see `motiontrack list`)")
    p.add_argument("--config", help="TOML config file (applied after --preset)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="STAGE.PARAM=VALUE",
                   help="override one config field (repeatable)")
    p.add_argument("--scene", metavar="FILE",
                   help="scene file (lines, zones; docs/analytics.md) for every video without its "
                        "own: each video's folder gets its events.jsonl and counts.csv")
    p.add_argument("--camera", metavar="FILE",
                   help="camera calibration for every video without its own (speeds and "
                        "positions in metres)")
    p.add_argument("--gt-from", metavar="MANIFEST",
                   help="manifest of [[sequence]] tables giving ground truth (and scene, camera) "
                        "to the videos of the same name or source: their index rows get "
                        "HOTA/MOTA/IDF1 and combined.json combines them")
    where = p.add_mutually_exclusive_group()
    where.add_argument("-j", "--jobs", type=int, default=1,
                       help="worker processes of a local Dask cluster (default 1)")
    where.add_argument("--cluster", metavar="ADDR",
                       help="address of a running Dask scheduler, e.g. tcp://host:8786")
    p.add_argument("--resume", action="store_true",
                   help="keep the videos whose results are complete with this config; redo the rest")
    p.add_argument("--retries", type=int, default=2,
                   help="times a video is run again when its worker dies (default 2)")
    p.add_argument("--timeout-s", type=float, default=3600, metavar="S",
                   help="a video still running after S seconds stops and is a `timeout` row "
                        "(default 3600)")
    p.set_defaults(func=cmd_batch)


def cmd_batch(args) -> int:
    from tqdm import tqdm

    from ..batch import run_batch
    from ..batch.combined import COMBINED_FILE
    from ..batch.counts import COUNTS_FILE, TOTALS_FILE
    from ..config import load_config
    from ._common import sigterm_as_interrupt

    cfg = load_config(args.config, args.overrides, preset=args.preset)
    with sigterm_as_interrupt(), tqdm(total=None, unit="video", disable=None, file=sys.stderr,
                                      dynamic_ncols=True) as bar:
        def progress(c) -> None:
            bar.total = c["total"]
            bar.n = c["done"] + c["failed"]
            bar.set_postfix_str(f"done={c['done']} failed={c['failed']} running={c['running']} "
                                f"frames={c['frames']} {c['fps']:.0f} fps", refresh=False)
            bar.refresh()

        try:
            rows = run_batch(args.sources, args.out, cfg, jobs=args.jobs, cluster=args.cluster,
                             resume=args.resume, retries=args.retries,
                             timeout_s=args.timeout_s, scene=args.scene, camera=args.camera,
                             gt_from=args.gt_from, progress=progress)
        except KeyboardInterrupt:
            bar.close()
            print(f"interrupted; the videos done are kept, the others are `interrupted` in "
                  f"{args.out}/index.csv (--resume finishes them)", file=sys.stderr)
            raise
    failed = [r for r in rows if r.get("status") != "done"]
    cut = sum(r.get("status") == "truncated" for r in rows)
    print(f"{len(rows) - len(failed)} done, " + (f"{cut} truncated, " if cut else "")
          + f"{len(failed) - cut} failed; index: {args.out}/index.csv")
    combined = Path(args.out) / COMBINED_FILE
    if combined.is_file():
        c = json.loads(combined.read_text(encoding="utf-8"))
        m = c["metrics"]
        print(f"combined over {len(c['sequences'])} videos with ground truth: "
              + "  ".join(f"{k} {m[k]:.4f}" for k in ("HOTA", "MOTA", "IDF1") if k in m)
              + f"; {combined}")
    totals = Path(args.out) / TOTALS_FILE
    if totals.is_file():
        t = json.loads(totals.read_text(encoding="utf-8"))
        print(f"events of {len(t['videos'])} videos with a scene: "
              f"{Path(args.out) / COUNTS_FILE} (per video), {totals} (totals)")
    for r in failed:
        print(f"  {r['name']}: {r.get('error', '')}", file=sys.stderr)
    return 1 if failed else 0
