"""Seed sweeps of the synthetic scenes through the whole pipeline: the figures of
docs/pipeline.md "Scenario seed sweeps" and the checks the test suite makes at one seed, here at
every seed.

The test suite tracks each synthetic scenario at one seed (tests/analytics/test_scene_events_tracked.py,
tests/analytics/test_abandoned.py); this script runs the same scenarios over many seeds. Three sweeps:

``identity``
    ``motiontrack track "synth:SCENE?seed=K" --no-video`` (default settings) for ``crossing``
    and ``column``, seeds 0-39: per scene the seeds with an identity switch, the switches in all,
    the mean HOTA / MOTA / IDF1 (default TrackEval scoring) and the lowest seed's MOTA.
``events``
    ``synth-events`` then ``track --scene`` for ``walker``, ``runner``, ``crossing`` and
    ``loiter`` (seeds 0-9): line counts per direction, zone entries and exits and the totals of
    ``summary.json`` equal the ground truth, every event is found within a second; ``loiter``
    fires within 0.5 s of the ground truth's; ``crowd``: each direction's count within one.
``abandoned``
    the whole pipeline with each scene's own scene file: ``leftbag`` seeds 0-9 give its one
    abandoned event within a second (with its owner), seeds 0-2 the bag's stationary events;
    ``walker``, ``crossing`` and ``crowd`` seeds 0-2 give no abandoned event.

Each sweep prints one row per seed that misses and a summary; the exit status is 1 when a check
of ``events`` or ``abandoned`` fails at any seed. A run takes 1-3 s; the defaults make
about 150 of them.

Run: .venv/bin/python benchmarks/seed_sweeps.py [identity] [events] [abandoned]
         [--seeds 0-39] [--event-seeds 0-9]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import logging
import sys
import tempfile
from collections import Counter
from pathlib import Path

from motiontrack.analytics import Analytics, parse_scene
from motiontrack.cli import main
from motiontrack.config import PipelineConfig
from motiontrack.evaluate.events import evaluate_events
from motiontrack.io.events import read_events
from motiontrack.pipeline import open_configured_source
from motiontrack.run.processors import TrackProcessor
from motiontrack.synth import make_scene
from scene_events import seeds_arg  # benchmarks/ is the script's folder, first on sys.path

IDENTITY_SCENES = {"crossing": "two people crossing", "column": "a person passing behind a column"}
EXACT_SCENES = ("walker", "runner", "crossing", "loiter")
DIRECTIONS = (("gate", "in"), ("gate", "out"))
SWEEPS = ("identity", "events", "abandoned")


def quiet_main(argv: list[str]) -> None:
    """``motiontrack ARGV`` in this process, its printout dropped; raises on a non-zero exit."""
    with contextlib.redirect_stdout(io.StringIO()):
        code = main([*argv, "-q"])
    if code != 0:
        raise RuntimeError(f"motiontrack {' '.join(argv)} exited {code}")


# ------------------------------------------------------------------------------- identity
def identity(seeds: list[int], scratch: Path) -> None:
    print("| scene | seeds with an identity switch | switches in all "
          "| mean HOTA / MOTA / IDF1 (lowest seed's MOTA) |")
    print("|---|---|---|---|")
    for name, what in IDENTITY_SCENES.items():
        acc = []
        for k in seeds:
            out = scratch / f"identity-{name}-{k}"
            quiet_main(["track", f"synth:{name}?seed={k}", "--no-video", "-o", str(out)])
            acc.append(json.loads((out / "summary.json").read_text())["accuracy"])
        switched = [k for k, a in zip(seeds, acc) if a["IDSW"] > 0]
        mean = {m: sum(a[m] for a in acc) / len(acc) for m in ("HOTA", "MOTA", "IDF1")}
        which = f" (seed{'s' if len(switched) > 1 else ''} " + \
            " and ".join(map(str, switched)) + ")" if switched else ""
        print(f"| `synth:{name}` ({what}) | {len(switched)} of {len(seeds)}{which} "
              f"| {sum(int(a['IDSW']) for a in acc)} "
              f"| {mean['HOTA']:.3f} / {mean['MOTA']:.3f} / {mean['IDF1']:.3f} "
              f"({min(a['MOTA'] for a in acc):.3f}) |")


# --------------------------------------------------------------------------------- events
def tracked(name: str, seed: int, scratch: Path):
    """Ground-truth events, tracked events and summary of ``track --scene`` on one scene."""
    spec, d = f"synth:{name}?seed={seed}", scratch / f"events-{name}-{seed}"
    quiet_main(["synth-events", spec, "-o", str(d / "gt")])
    quiet_main(["track", spec, "--scene", str(d / "gt" / "scene.toml"), "--no-video",
                "-o", str(d / "run")])
    return (read_events(d / "gt" / "events.jsonl").events,
            read_events(d / "run" / "events.jsonl").events,
            json.loads((d / "run" / "summary.json").read_text()))


def crossings(events) -> Counter:
    return Counter((e.line, e.direction) for e in events if e.type == "line_cross")


def count(events, kind: str) -> int:
    return sum(e.type == kind for e in events)


def exact_misses(name: str, gt, pred, summary) -> list[str]:
    """What differs from the ground truth in a scene where everything is exact."""
    miss = []
    g, p = crossings(gt), crossings(pred)
    if any(p[k] != g[k] for k in DIRECTIONS):
        miss.append(f"gate in/out {p['gate', 'in']}/{p['gate', 'out']} "
                    f"(truth {g['gate', 'in']}/{g['gate', 'out']})")
    lines = summary["analytics"]["lines"]["gate"]
    if (lines["in"], lines["out"]) != (g["gate", "in"], g["gate", "out"]):
        miss.append(f"summary gate in/out {lines['in']}/{lines['out']}")
    for kind in ("zone_enter", "zone_exit"):
        if count(pred, kind) != count(gt, kind):
            miss.append(f"{kind} {count(pred, kind)} (truth {count(gt, kind)})")
    zone = summary["analytics"]["zones"]["plaza"]
    if (zone["enters"], zone["exits"]) != (count(gt, "zone_enter"), count(gt, "zone_exit")):
        miss.append(f"summary plaza enters/exits {zone['enters']}/{zone['exits']}")
    total = evaluate_events(gt, pred, tolerance_s=1.0).total
    if (total.tp, total.fp, total.fn) != (len(gt), 0, 0):
        miss.append(f"events TP/FP/FN {total.tp}/{total.fp}/{total.fn} of {len(gt)}")
    if name == "loiter":
        g_l = [e for e in gt if e.type == "loiter"]
        p_l = [e for e in pred if e.type == "loiter"]
        if len(g_l) != 1 or len(p_l) != 1 or p_l[0].zone != g_l[0].zone \
                or abs(p_l[0].t - g_l[0].t) > 0.5:
            miss.append(f"loiter at {[e.t for e in p_l]} (truth {[e.t for e in g_l]})")
    return miss


def events(seeds: list[int], scratch: Path) -> bool:
    ok = True
    print()
    print("| scene | seeds | runs with everything as the ground truth |")
    print("|---|---|---|")
    rows = []
    for name in (*EXACT_SCENES, "crowd"):
        good = 0
        for k in seeds:
            gt, pred, summary = tracked(name, k, scratch)
            if name == "crowd":
                g, p = crossings(gt), crossings(pred)
                miss = [f"{d} {p[d]} (truth {g[d]})" for d in DIRECTIONS if abs(p[d] - g[d]) > 1]
            else:
                miss = exact_misses(name, gt, pred, summary)
            good += not miss
            rows += [f"  {name} seed {k}: {m}" for m in miss]
        ok &= good == len(seeds)
        print(f"| `{name}`{' (line counts within one)' if name == 'crowd' else ''} "
              f"| {seeds[0]}–{seeds[-1]} | {good}/{len(seeds)} |")
    for row in rows:
        print(row)
    return ok


# ------------------------------------------------------------------------------ abandoned
def scene_events(name: str, seed: int):
    """Every scene event of the whole pipeline on a synthetic scene with its own scene file."""
    s = make_scene(name, seed=seed)
    cfg = PipelineConfig()
    src = open_configured_source(s.spec, cfg.source)
    proc = TrackProcessor(cfg, src.info,
                          analytics=Analytics(parse_scene(s.scene_file), src.info.fps or 25.0))
    try:
        return s, [e for r in proc.results(src) for e in r.scene.events]
    finally:
        src.close()


def abandoned(seeds: list[int]) -> bool:
    logging.getLogger("motiontrack").setLevel(logging.ERROR)
    rows, found, still, clean = [], 0, 0, 0
    still_seeds = [k for k in seeds if k < 3]
    for k in seeds:
        s, ev = scene_events("leftbag", k)
        gt = [e for e in s.ground_truth_events() if e.type == "abandoned"]
        pred = [e for e in ev if e.type == "abandoned"]
        score = evaluate_events(gt, pred, tolerance_s=1.0).by_type["abandoned"]
        if (score.gt, score.pred, score.tp) == (1, 1, 1) and pred[0].owner == gt[0].owner:
            found += 1
        else:
            rows.append(f"  leftbag seed {k}: abandoned {[(e.t, e.owner) for e in pred]} "
                        f"(truth {[(e.t, e.owner) for e in gt]})")
        if k in still_seeds:
            gt_s = [e for e in s.ground_truth_events() if e.type.startswith("stationary")]
            pred_s = [e for e in ev if e.type.startswith("stationary")]
            if gt_s and evaluate_events(gt_s, pred_s, tolerance_s=1.0).total.f1 == 1.0:
                still += 1
            else:
                rows.append(f"  leftbag seed {k}: stationary events differ from the truth")
    others = [(n, k) for n in ("walker", "crossing", "crowd") for k in still_seeds]
    for name, k in others:
        if [e for e in scene_events(name, k)[1] if e.type == "abandoned"]:
            rows.append(f"  {name} seed {k}: an abandoned event without a bag")
        else:
            clean += 1
    print()
    print(f"leftbag abandoned found within 1 s with its owner: {found}/{len(seeds)}; "
          f"bag stationary as the truth: {still}/{len(still_seeds)}; "
          f"no abandoned event without a bag: {clean}/{len(others)}")
    for row in rows:
        print(row)
    return not rows


def main_(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("sweeps", nargs="*", metavar="identity|events|abandoned",
                    help="which sweeps (default: all three)")
    ap.add_argument("--seeds", type=seeds_arg, default=seeds_arg("0-39"),
                    help="seeds of the identity sweep (default 0-39)")
    ap.add_argument("--event-seeds", type=seeds_arg, default=seeds_arg("0-9"),
                    help="seeds of the events and abandoned sweeps (default 0-9)")
    args = ap.parse_args(argv)
    sweeps = args.sweeps or list(SWEEPS)
    if set(sweeps) - set(SWEEPS):
        ap.error(f"unknown sweep {sorted(set(sweeps) - set(SWEEPS))}; the sweeps are {SWEEPS}")
    ok = True
    with tempfile.TemporaryDirectory(prefix="seed_sweeps_") as scratch:
        if "identity" in sweeps:
            identity(args.seeds, Path(scratch))
        if "events" in sweeps:
            ok &= events(args.event_seeds, Path(scratch))
        if "abandoned" in sweeps:
            ok &= abandoned(args.event_seeds)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main_())
