#!/usr/bin/env python3
"""Run TrackEval (the MOTChallenge reference implementation) and dump its numbers as golden JSON.

TrackEval cannot live in motiontrack's environment (it pins numpy/opencv versions that conflict
with ours), so run this script with the python of a separate virtual environment::

    python3 -m venv /tmp/te-venv
    /tmp/te-venv/bin/pip install trackeval==1.3.0
    /tmp/te-venv/bin/python tools/trackeval_golden.py --name tud-campus --benchmark MOT15 \
        --gt ../shared/data/tud-campus/gt.txt --pred ../shared/data/tud-campus/test.txt \
        --out tests/golden/tud-campus.json

Several sequences are evaluated together (and combined as TrackEval combines them) by repeating
``--gt``/``--pred`` in pairs (``--seq-name`` optionally names each). The script only uses the
standard library and TrackEval; it copies the files into a temporary MOTChallenge layout, runs
``trackeval.Evaluator`` with ``MotChallenge2DBox`` and the HOTA, CLEAR and Identity metrics, and
writes ``{"trackeval_version", "benchmark", "sequences": {seq: {field: value}}, "combined": {...}}``
with TrackEval's field names (HOTA fields are lists over alpha = 0.05..0.95).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path


def _max_frame(path: Path) -> int:
    last = 0
    for line in path.read_text().splitlines():
        line = line.strip()
        if line:
            last = max(last, int(float(line.replace(" ", "").split(",")[0])))
    return last


def _jsonable(v):
    try:
        import numpy as np
    except ImportError:  # pragma: no cover
        np = None
    if np is not None and isinstance(v, np.ndarray):
        return [float(x) for x in v.tolist()]
    if np is not None and isinstance(v, np.generic):
        return v.item()
    return v


def run(gts: list[Path], preds: list[Path], names: list[str], benchmark: str,
        lengths: list[int] | None = None, do_preproc: bool = True) -> dict:
    import trackeval  # noqa: PLC0415 - only inside the TrackEval venv

    tmp = Path(tempfile.mkdtemp(prefix="te-golden-"))
    try:
        gt_root, tr_root = tmp / "gt", tmp / "trackers"
        seq_info = {}
        for i, (g, p, n) in enumerate(zip(gts, preds, names)):
            (gt_root / n / "gt").mkdir(parents=True)
            shutil.copy(g, gt_root / n / "gt" / "gt.txt")
            (tr_root / "tracker" / "data").mkdir(parents=True, exist_ok=True)
            shutil.copy(p, tr_root / "tracker" / "data" / f"{n}.txt")
            length = lengths[i] if lengths else max(_max_frame(g), _max_frame(p))
            seq_info[n] = length
            (gt_root / n / "seqinfo.ini").write_text(
                f"[Sequence]\nname={n}\nseqLength={length}\n")
        eval_cfg = trackeval.Evaluator.get_default_eval_config()
        eval_cfg.update({"USE_PARALLEL": False, "PRINT_RESULTS": False, "PRINT_CONFIG": False,
                         "TIME_PROGRESS": False, "OUTPUT_SUMMARY": False, "OUTPUT_DETAILED": False,
                         "PLOT_CURVES": False, "DISPLAY_LESS_PROGRESS": True})
        ds_cfg = trackeval.datasets.MotChallenge2DBox.get_default_dataset_config()
        ds_cfg.update({"GT_FOLDER": str(gt_root), "TRACKERS_FOLDER": str(tr_root),
                       "OUTPUT_FOLDER": str(tmp / "out"), "TRACKERS_TO_EVAL": ["tracker"],
                       "BENCHMARK": benchmark, "SEQ_INFO": seq_info, "SKIP_SPLIT_FOL": True,
                       "DO_PREPROC": do_preproc, "PRINT_CONFIG": False})
        evaluator = trackeval.Evaluator(eval_cfg)
        dataset = trackeval.datasets.MotChallenge2DBox(ds_cfg)
        metrics = [trackeval.metrics.HOTA({"PRINT_CONFIG": False}),
                   trackeval.metrics.CLEAR({"PRINT_CONFIG": False}),
                   trackeval.metrics.Identity({"PRINT_CONFIG": False})]
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(io.StringIO()):
            out, msg = evaluator.evaluate([dataset], metrics)
        elapsed = time.perf_counter() - t0
        res = out["MotChallenge2DBox"]["tracker"]
        if not isinstance(res, dict):
            raise RuntimeError(f"TrackEval failed: {msg}")
        flat = {}
        for seq, by_cls in res.items():
            d = {}
            for fam in ("HOTA", "CLEAR", "Identity"):
                for k, v in by_cls["pedestrian"][fam].items():
                    d[k] = _jsonable(v)
            flat["combined" if seq == "COMBINED_SEQ" else seq] = d
        return {"trackeval_version": getattr(trackeval, "__version__", "1.3.0"),
                "benchmark": benchmark, "do_preproc": do_preproc, "seq_lengths": seq_info,
                "sequences": {k: v for k, v in flat.items() if k != "combined"},
                "combined": flat["combined"], "elapsed_s": elapsed}
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


# --------------------------------------------------------------------------------------------------
# deterministic inputs for the golden cases (stdlib only: random.Random is stable across versions)
# --------------------------------------------------------------------------------------------------
def perturb_gt(gt_path: Path, seed: int) -> str:
    """A synthetic tracker output from a MOT17 gt file: every gt row (all classes, so that the
    distractor preprocessing matters) is dropped (12 %), jittered, sometimes pushed below IoU 0.5;
    two ids swap half-way, one track restarts with a new id; 0-2 false positives per frame."""
    import random

    rng = random.Random(seed)
    rows = [[float(t) for t in line.split(",")] for line in gt_path.read_text().split()]
    ids = sorted({int(r[1]) for r in rows})
    frames = sorted({int(r[0]) for r in rows})
    mid = frames[len(frames) // 2]
    swap = rng.sample(ids, 2) if len(ids) >= 2 else ids * 2
    restart = rng.choice(ids)
    out = []
    for r in rows:
        f, i, x, y, w, h = int(r[0]), int(r[1]), r[2], r[3], r[4], r[5]
        if rng.random() < 0.12:
            continue
        shift = 0.6 if rng.random() < 0.08 else 0.06
        x += rng.uniform(-shift, shift) * w
        y += rng.uniform(-shift, shift) * h
        w *= rng.uniform(0.9, 1.1)
        h *= rng.uniform(0.9, 1.1)
        if f >= mid and i in swap:
            i = swap[1] if i == swap[0] else swap[0]
        if f >= mid and i == restart:
            i += 1000
        out.append((f, i, x, y, w, h))
    for f in frames:
        for k in range(rng.randint(0, 2)):
            out.append((f, 5000 + 10 * f + k, rng.uniform(0, 1500), rng.uniform(0, 800),
                        rng.uniform(20, 120), rng.uniform(40, 250)))
    out.sort(key=lambda t: (t[0], t[1]))
    return "".join(f"{f},{i},{x:.2f},{y:.2f},{w:.2f},{h:.2f},1,-1,-1,-1\n" for f, i, x, y, w, h in out)


def make_inputs(data: Path, out: Path, seqs: list[str]) -> None:
    """Write ``out/<seq>.pred.txt`` perturbed trackers for the mot17-mini sequences."""
    out.mkdir(parents=True, exist_ok=True)
    for k, s in enumerate(seqs):
        (out / f"{s}.pred.txt").write_text(perturb_gt(data / s / "gt" / "gt.txt", seed=17 + k))


def _rel(path: Path, base: Path, data_root: Path | None) -> str:
    path = path.resolve()
    if data_root is not None:
        try:
            return "data:" + path.relative_to(data_root.resolve()).as_posix()
        except ValueError:
            pass
    return os.path.relpath(path, base.resolve())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--make-inputs", nargs="+", metavar=("DATA_TRAIN_DIR", "SEQ"),
                    help="write perturbed tracker files for these mot17-mini sequences into --out "
                         "(a folder) and exit; needs no TrackEval")
    ap.add_argument("--gt", action="append", type=Path)
    ap.add_argument("--pred", action="append", type=Path)
    ap.add_argument("--seq-name", action="append")
    ap.add_argument("--length", action="append", type=int, help="sequence length (default: last frame)")
    ap.add_argument("--benchmark", default="MOT17", help="MOT15 (no classes) / MOT16 / MOT17 / MOT20")
    ap.add_argument("--no-preproc", action="store_true")
    ap.add_argument("--keep-time", action="store_true",
                    help="store TrackEval's evaluation time (loading + metrics) as elapsed_s")
    ap.add_argument("--data-root", type=Path, help="shared data root (recorded as 'data:...')")
    ap.add_argument("--name", help="case name stored in the JSON")
    ap.add_argument("--out", required=True, type=Path)
    a = ap.parse_args(argv)
    if a.make_inputs:
        make_inputs(Path(a.make_inputs[0]), a.out, a.make_inputs[1:])
        return 0
    if not a.gt or not a.pred or not a.name:
        ap.error("--gt, --pred and --name are required")
    if len(a.gt) != len(a.pred):
        ap.error("give --gt and --pred in pairs")
    names = a.seq_name or [f"SEQ{i + 1:02d}" for i in range(len(a.gt))]
    res = run(a.gt, a.pred, names, a.benchmark, a.length, not a.no_preproc)
    if not a.keep_time:
        res.pop("elapsed_s")
    res["name"] = a.name
    # paths relative to the JSON file's folder; "data:" marks the shared real-data root
    res["inputs"] = [{"seq": n, "gt": _rel(g, a.out.parent, a.data_root),
                      "pred": _rel(p, a.out.parent, a.data_root)}
                     for n, g, p in zip(names, a.gt, a.pred)]
    a.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = a.out.with_suffix(".json.part")
    tmp.write_text(json.dumps(res, indent=1, sort_keys=True) + "\n")
    os.replace(tmp, a.out)
    print(f"wrote {a.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
