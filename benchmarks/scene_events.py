"""Scene analytics end to end on the synthetic scenes: ``motiontrack track SPEC --scene`` (the
command users run, default settings, no annotated video) against each scene's exact
ground-truth events.

For every scene and seed it writes the scene file (``scene.scene_toml()``, what ``synth-events``
writes), runs ``track`` with it, reads the run's ``events.jsonl`` and compares it with
``scene.ground_truth_events()``: line crossings per line and direction, zone entries and exits,
loiter times, and ``evaluate-events`` (tolerance 1 s) totals. It prints one row per run with
``--runs``, and one row per scene: the counts summed over the seeds as ``tracked/ground truth``,
how many runs had every line count exact, and the F1 over all the scene's events.

Run: .venv/bin/python benchmarks/scene_events.py [--scenes walker,runner,crossing,crowd,loiter]
         [--seeds 0-9] [--runs] [--keep DIR]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

from motiontrack.cli import main
from motiontrack.evaluate.events import evaluate_events
from motiontrack.io.events import read_events
from motiontrack.synth import make_scene

SCENES = ("walker", "runner", "crossing", "crowd", "loiter")


def tally(events) -> Counter:
    """Counts per ``(type, line or zone, direction)``."""
    return Counter((e.type, e.line or e.zone or "", e.direction or "") for e in events)


def run_one(name: str, seed: int, folder: Path) -> dict:
    """``track --scene`` on one synthetic scene; ground truth and tracked events, counts, F1."""
    scene = make_scene(name, seed=seed)
    spec = f"synth:{name}?seed={seed}"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "scene.toml").write_text(scene.scene_toml())
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        code = main(["track", spec, "--scene", str(folder / "scene.toml"), "--no-video",
                     "-o", str(folder / "run"), "--force"])
    if code != 0:
        raise RuntimeError(f"track {spec} exited {code}")
    seconds = time.perf_counter() - t0
    gt = scene.ground_truth_events()
    pred = read_events(folder / "run" / "events.jsonl").events
    ev = evaluate_events(gt, pred, tolerance_s=1.0)
    return {"scene": name, "seed": seed, "gt": gt, "pred": pred, "gt_counts": tally(gt),
            "pred_counts": tally(pred), "total": ev.total, "seconds": seconds,
            "frames": scene.n_frames}


def loiter_dt(r: dict) -> list[float]:
    """Tracked minus ground-truth time of each ``loiter`` (paired in time order)."""
    g = sorted(e.t for e in r["gt"] if e.type == "loiter")
    p = sorted(e.t for e in r["pred"] if e.type == "loiter")
    return [b - a for a, b in zip(g, p)] if len(g) == len(p) else []


def seeds_arg(text: str) -> list[int]:
    out: list[int] = []
    for part in text.split(","):
        a, _, b = part.partition("-")
        out += list(range(int(a), int(b or a) + 1))
    return out


def fmt(counts: tuple[Counter, Counter], key: tuple[str, str, str]) -> str:
    pred, gt = counts
    return f"{pred[key]}/{gt[key]}"


def main_(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--seeds", default="0-9", type=seeds_arg)
    ap.add_argument("--runs", action="store_true", help="also print one row per run")
    ap.add_argument("--keep", type=Path, help="keep the runs in this folder")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="scene_events_") as scratch:
        base = args.keep or Path(scratch)
        results: dict[str, list[dict]] = {}
        for name in args.scenes.split(","):
            for seed in args.seeds:
                r = run_one(name, seed, base / f"{name}-{seed}")
                results.setdefault(name, []).append(r)
                print(f"  {name} seed {seed}: {r['frames']} frames in {r['seconds']:.1f} s",
                      file=sys.stderr)
    cross = [("line_cross", "gate", "in"), ("line_cross", "gate", "out")]
    zone = [("zone_enter", "plaza", ""), ("zone_exit", "plaza", "")]
    columns = ["scene", "seeds", "gate in", "gate out", "lines exact", "plaza enter",
               "plaza exit", "loiter", r"loiter max \|Δt\|", "GT", "Pred", "TP", "F1"]
    if args.runs:
        print("| scene | seed | gate in | gate out | plaza enter | plaza exit | loiter Δt s "
              "| TP/GT/Pred | F1 |")
        print("|---|---|---|---|---|---|---|---|---|")
        for name, rs in results.items():
            for r in rs:
                c = (r["pred_counts"], r["gt_counts"])
                dt = " ".join(f"{d:+.2f}" for d in loiter_dt(r)) or "-"
                tot = r["total"]
                print(f"| `{name}` | {r['seed']} | {fmt(c, cross[0])} | {fmt(c, cross[1])} "
                      f"| {fmt(c, zone[0])} | {fmt(c, zone[1])} | {dt} "
                      f"| {tot.tp}/{tot.gt}/{tot.pred} | {tot.f1:.3f} |")
        print()
    print("tracked/ground truth, summed over the seeds; lines exact: runs whose every line "
          "count is the ground truth's; F1: evaluate-events, tolerance 1 s, all events")
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))
    for name, rs in results.items():
        pred = sum((r["pred_counts"] for r in rs), Counter())
        gt = sum((r["gt_counts"] for r in rs), Counter())
        c = (pred, gt)
        exact = sum(all(r["pred_counts"][k] == r["gt_counts"][k] for k in cross) for r in rs)
        dts = [abs(d) for r in rs for d in loiter_dt(r)]
        tot = sum((r["total"] for r in rs[1:]), rs[0]["total"])
        seeds = f"{rs[0]['seed']}–{rs[-1]['seed']}" if len(rs) > 1 else str(rs[0]["seed"])
        print(f"| `{name}` | {seeds} | {fmt(c, cross[0])} | {fmt(c, cross[1])} "
              f"| {exact}/{len(rs)} | {fmt(c, zone[0])} | {fmt(c, zone[1])} "
              f"| {fmt(c, ('loiter', 'plaza', ''))} | {f'{max(dts):.2f} s' if dts else '–'} "
              f"| {tot.gt} | {tot.pred} | {tot.tp} | {tot.f1:.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main_())
