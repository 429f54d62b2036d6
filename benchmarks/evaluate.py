#!/usr/bin/env python3
"""Speed of HOTA + CLEAR + Identity against TrackEval, on one core, with identical numbers.

Inputs: a synthetic sequence (default 5,000 frames x 30 objects, deterministic) and TUD-Campus
from the shared data. Ours is timed in-process (reading the MOT files + preprocessing + the three
metric families, best of ``--repeat``); TrackEval runs in its own virtual environment through
``tools/trackeval_golden.py`` in a subprocess, which times ``Evaluator.evaluate`` (its file
loading + preprocessing + metrics, without interpreter start-up and imports).

    .venv/bin/python benchmarks/evaluate.py --trackeval-python /tmp/te-venv/bin/python

``--trackeval-python`` defaults to ``$TRACKEVAL_PYTHON``; without it only our times are printed.
The process (and so the subprocess) is pinned to one CPU and BLAS threads are set to 1.

Benchmark folders, end to end (``--run-mot-challenge``, default ``$RUN_MOT_CHALLENGE``: TrackEval's
``scripts/run_mot_challenge.py`` from its sdist, see ``tools/mot_benchmark_golden.py``): the
command ``motiontrack evaluate --gt-folder SPLIT --trackers-folder TRACKERS --json OUT`` and
``run_mot_challenge.py --GT_FOLDER SPLIT --TRACKERS_FOLDER TRACKERS --SKIP_SPLIT_FOL True
--SEQ_INFO <sequences>`` (its defaults otherwise: summary, detailed CSV and plots written) each
run as a new process, wall-clock and CPU time from process start to exit, median of ``--runs``,
on (a) mot17-mini with three trackers and (b) a synthetic MOT17-layout benchmark (default 20
sequences x 1,000 frames x 20 objects, classes and zero-marked rows included, two trackers).
Every number of every sequence and of COMBINED is compared (our JSON against TrackEval's
``pedestrian_detailed.csv``)::

    .venv/bin/python benchmarks/evaluate.py --trackeval-python /tmp/te-venv/bin/python \
        --run-mot-challenge /tmp/te-sdist/trackeval-1.3.0/scripts/run_mot_challenge.py --folders-only
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "src"))

from motiontrack.evaluate import mot  # noqa: E402
from motiontrack.io.mot import read_mot  # noqa: E402


def synthetic(frames: int, objects: int, seed: int = 0) -> tuple[str, str]:
    """MOT15-style gt and tracker text: ``objects`` walkers alive at a time (each lives 50-400
    frames, replaced on death), the tracker jitters boxes, misses 10 %, swaps ids now and then,
    and adds ~2 false positives per frame."""
    rng = np.random.default_rng(seed)
    gt_rows, tr_rows = [], []
    next_id = 1
    state = []  # [id, x, y, vx, vy, w, h, death, tracker id]
    for f in range(1, frames + 1):
        state = [s for s in state if s[7] > f]
        while len(state) < objects:
            w = rng.uniform(20, 60)
            state.append([next_id, rng.uniform(0, 1800), rng.uniform(0, 1000), rng.normal(0, 2),
                          rng.normal(0, 1), w, w * rng.uniform(2, 3), f + rng.integers(50, 400),
                          next_id + 100000])
            next_id += 1
        if f % 25 == 0 and len(state) > 2:  # an identity switch between two tracks
            i, j = rng.choice(len(state), 2, replace=False)
            state[i][8], state[j][8] = state[j][8], state[i][8]
        for s in state:
            s[1] += s[3]
            s[2] += s[4]
            gt_rows.append(f"{f},{s[0]},{s[1]:.2f},{s[2]:.2f},{s[5]:.2f},{s[6]:.2f},1,-1,-1,-1\n")
            if rng.random() < 0.9:
                j = rng.normal(0, 0.08, 4) * [s[5], s[6], s[5], s[6]]
                tr_rows.append(f"{f},{s[8]},{s[1] + j[0]:.2f},{s[2] + j[1]:.2f},"
                               f"{s[5] + abs(j[2]):.2f},{s[6] + abs(j[3]):.2f},1,-1,-1,-1\n")
        for k in range(rng.poisson(2)):
            tr_rows.append(f"{f},{900000 + f * 10 + k},{rng.uniform(0, 1800):.2f},"
                           f"{rng.uniform(0, 1000):.2f},40,100,1,-1,-1,-1\n")
    return "".join(gt_rows), "".join(tr_rows)


def ours(gt: Path, pred: Path, length: int, repeat: int) -> tuple[float, float, dict]:
    """Best-of-``repeat`` seconds for reading both files and for the metrics, and the results."""
    t_read = t_eval = float("inf")
    res: dict = {}
    for _ in range(repeat):
        t0 = time.perf_counter()
        g = read_mot(gt, kind="gt")
        p = read_mot(pred, kind="results")
        t1 = time.perf_counter()
        res = mot.evaluate_sequence(g, p, num_timesteps=length)
        t2 = time.perf_counter()
        t_read, t_eval = min(t_read, t1 - t0), min(t_eval, t2 - t1)
    return t_read, t_eval, res


def trackeval(python: str, gt: Path, pred: Path, length: int, benchmark: str) -> tuple[float, dict]:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "te.json"
        subprocess.run([python, str(REPO / "tools" / "trackeval_golden.py"), "--name", "bench",
                        "--benchmark", benchmark, "--gt", str(gt), "--pred", str(pred),
                        "--seq-name", "SEQ", "--length", str(length), "--keep-time",
                        "--out", str(out)], check=True, capture_output=True)
        d = json.loads(out.read_text())
    return d["elapsed_s"], d["sequences"]["SEQ"]


def max_diff(res: dict, ref: dict) -> float:
    ours_flat = {k: v for fam in res.values() for k, v in fam.items()}
    return max(float(np.max(np.abs(np.asarray(ours_flat[k], float) - np.asarray(v, float))))
               for k, v in ref.items())


# --------------------------------------------------------------------------------------------------
# benchmark folders end to end: motiontrack evaluate --gt-folder vs TrackEval's run_mot_challenge.py
# --------------------------------------------------------------------------------------------------
sys.path.insert(0, str(REPO / "tools"))
from mot_benchmark_golden import make_trackers, read_detailed, run_mot_challenge_cmd  # noqa: E402

#: our JSON key -> TrackEval's pedestrian_detailed.csv column
TE_COLUMNS = {"HOTA": "HOTA___AUC", "DetA": "DetA___AUC", "AssA": "AssA___AUC",
              "LocA": "LocA___AUC", "DetRe": "DetRe___AUC", "DetPr": "DetPr___AUC",
              "AssRe": "AssRe___AUC", "AssPr": "AssPr___AUC", "HOTA(0)": "HOTA(0)",
              "LocA(0)": "LocA(0)", "MOTA": "MOTA", "MOTP": "MOTP", "MODA": "MODA",
              "sMOTA": "sMOTA", "recall": "CLR_Re", "precision": "CLR_Pr", "TP": "CLR_TP",
              "FN": "CLR_FN", "FP": "CLR_FP", "IDSW": "IDSW", "MT": "MT", "PT": "PT", "ML": "ML",
              "Frag": "Frag", "IDF1": "IDF1", "IDR": "IDR", "IDP": "IDP", "IDTP": "IDTP",
              "IDFN": "IDFN", "IDFP": "IDFP"}


def synthetic_split(root: Path, seqs: int, frames: int, objects: int) -> tuple[Path, Path, list[str]]:
    """A MOT17-layout benchmark: ``root/split/<seq>/{gt/gt.txt,seqinfo.ini}`` (9-column gt with
    class 1, every 11th id a static person (distractor class 7), every 13th zero-marked) and
    ``root/trackers/{jitter,jitter-b}/data/<seq>.txt`` (:func:`synthetic` trackers of two seeds)."""
    split, trackers = root / "split", root / "trackers"
    names = [f"SYN-{k + 1:02d}" for k in range(seqs)]
    for k, name in enumerate(names):
        (split / name / "gt").mkdir(parents=True)
        (split / name / "seqinfo.ini").write_text(
            f"[Sequence]\nname={name}\nimDir=img1\nframeRate=30\nseqLength={frames}\n"
            "imWidth=1920\nimHeight=1080\nimExt=.jpg\n")
        for t, seed in (("jitter", 1000 + k), ("jitter-b", 2000 + k)):
            gt_text, tr_text = synthetic(frames, objects, seed)
            (trackers / t / "data").mkdir(parents=True, exist_ok=True)
            (trackers / t / "data" / f"{name}.txt").write_text(tr_text)
        gt_text, _ = synthetic(frames, objects, 1000 + k)  # the same world as "jitter" sees
        rows = []
        for line in gt_text.splitlines():
            f = line.split(",")
            i = int(f[1])
            klass, consider = (7 if i % 11 == 0 else 1), (0 if i % 13 == 0 else 1)
            rows.append(",".join(f[:6] + [str(consider), str(klass), "1.0"]) + "\n")
        (split / name / "gt" / "gt.txt").write_text("".join(rows))
    return split, trackers, names


def _timed(cmd: list[str], env: dict | None = None) -> tuple[float, float]:
    """Wall-clock and CPU seconds (user + system) of one process, start to exit."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def folders_case(name: str, split: Path, trackers: Path, seqs: list[str], te_python: str | None,
                 rmc: str | None, runs: int) -> dict:
    """Median end-to-end times of both commands on one benchmark folder, and the largest
    difference over every number of every tracker, sequence and COMBINED."""
    out = trackers.parent / "ours.json"
    ours_cmd = [sys.executable, "-m", "motiontrack", "evaluate", "--gt-folder", str(split),
                "--trackers-folder", str(trackers), "--json", str(out), "--force"]
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    ours = [_timed(ours_cmd, env) for _ in range(runs)]
    res = json.loads(out.read_text())
    row = {"case": name, "trackers": len(res), "sequences": len(seqs),
           "gt boxes": sum(len(read_mot(split / s / "gt" / "gt.txt", kind="gt")) for s in seqs),
           "ours s": statistics.median(w for w, _ in ours),
           "ours cpu s": statistics.median(c for _, c in ours)}
    if te_python and rmc:
        te_cmd = run_mot_challenge_cmd(te_python, rmc, split, trackers, seqs)
        te = [_timed(te_cmd) for _ in range(runs)]
        diff, n = 0.0, 0
        for t, rows in res.items():
            ref = read_detailed(trackers / t / "pedestrian_detailed.csv")
            assert sorted(ref) == sorted(rows), (t, sorted(ref), sorted(rows))
            for seq, flat in rows.items():
                for k, col in TE_COLUMNS.items():
                    diff = max(diff, abs(float(flat[k]) - ref[seq][col]))
                    n += 1
        row.update({"TrackEval s": statistics.median(w for w, _ in te),
                    "TrackEval cpu s": statistics.median(c for _, c in te)})
        row.update({"speed-up": row["TrackEval s"] / row["ours s"],
                    "speed-up cpu": row["TrackEval cpu s"] / row["ours cpu s"],
                    "numbers compared": n, "max |diff|": diff, "identical (1e-12)": diff <= 1e-12})
    return row


def print_table(rows: list[dict]) -> None:
    keys = list(dict.fromkeys(k for r in rows for k in r))

    def fmt(v):
        if isinstance(v, bool):
            return "yes" if v else "NO"
        if isinstance(v, float):
            return f"{v:.3g}" if abs(v) < 1e-3 and v else f"{v:.3f}"
        return str(v)

    table = [keys] + [[fmt(r.get(k, "-")) for k in keys] for r in rows]
    w = [max(len(t[i]) for t in table) for i in range(len(keys))]
    for i, t in enumerate(table):
        print("  ".join(c.ljust(x) for c, x in zip(t, w)))
        if i == 0:
            print("-" * (sum(w) + 2 * (len(w) - 1)))


def folders_main(a) -> None:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        mini = a.data / "mot17-mini" / "train"
        if mini.is_dir():
            trackers = Path(tmp) / "mini" / "trackers"
            seqs = make_trackers(mini, trackers)
            rows.append(folders_case("mot17-mini", mini, trackers, seqs, a.trackeval_python,
                                     a.run_mot_challenge, a.runs))
        split, trackers, seqs = synthetic_split(Path(tmp) / "syn", a.bench_seqs, a.bench_frames,
                                                a.bench_objects)
        rows.append(folders_case(f"synthetic {a.bench_seqs} seq x {a.bench_frames} frames x "
                                 f"{a.bench_objects}", split, trackers, seqs, a.trackeval_python,
                                 a.run_mot_challenge, a.runs_large or a.runs))
    print(f"end to end, one core, median of {a.runs} runs (synthetic: {a.runs_large or a.runs}); "
          "'speed-up' = TrackEval run_mot_challenge.py / motiontrack evaluate --gt-folder, wall "
          "clock ('cpu': user + system time)")
    print_table(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=5000)
    ap.add_argument("--objects", type=int, default=30)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--data", type=Path,
                    default=Path(os.environ.get("MOTIONTRACK_DATA", REPO.parent / "shared" / "data")))
    ap.add_argument("--trackeval-python", default=os.environ.get("TRACKEVAL_PYTHON"))
    ap.add_argument("--run-mot-challenge", default=os.environ.get("RUN_MOT_CHALLENGE"),
                    help="TrackEval's scripts/run_mot_challenge.py (benchmark folders)")
    ap.add_argument("--runs", type=int, default=3, help="runs per command (median), folders")
    ap.add_argument("--runs-large", type=int, default=None,
                    help="runs on the synthetic benchmark folder (default --runs)")
    ap.add_argument("--bench-seqs", type=int, default=20)
    ap.add_argument("--bench-frames", type=int, default=1000)
    ap.add_argument("--bench-objects", type=int, default=20)
    ap.add_argument("--folders-only", action="store_true",
                    help="only the benchmark folders, end to end")
    a = ap.parse_args(argv)
    try:
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        pass
    if a.folders_only:
        folders_main(a)
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        gt_text, tr_text = synthetic(a.frames, a.objects)
        sg, sp = Path(tmp) / "gt.txt", Path(tmp) / "pred.txt"
        sg.write_text(gt_text)
        sp.write_text(tr_text)
        cases = [(f"synthetic {a.frames}x{a.objects}", sg, sp, a.frames, "MOT15")]
        tud = a.data / "tud-campus"
        if (tud / "gt.txt").is_file():
            cases.append(("TUD-Campus", tud / "gt.txt", tud / "test.txt", 71, "MOT15"))
        rows = []
        for name, g, p, length, bench in cases:
            t_read, t_eval, res = ours(g, p, length, a.repeat)
            t_ours = t_read + t_eval
            row = {"case": name, "gt boxes": len(read_mot(g, kind="gt")), "ours read s": t_read,
                   "ours metrics s": t_eval, "ours total s": t_ours,
                   "HOTA": float(np.mean(res["hota"]["HOTA"])), "MOTA": res["clear"]["MOTA"],
                   "IDF1": res["identity"]["IDF1"]}
            if a.trackeval_python:
                t_te, ref = trackeval(a.trackeval_python, g, p, length, bench)
                d = max_diff(res, ref)
                row.update({"TrackEval s": t_te, "speed-up": t_te / t_ours,
                            "speed-up metrics": t_te / t_eval,
                            "max |diff|": d, "identical (1e-6)": d <= 1e-6})
            rows.append(row)
    print("one core; 'speed-up' = TrackEval (load + preprocess + metrics) / ours (read_mot + "
          "metrics); 'speed-up metrics' leaves out our file reading")
    print_table(rows)
    if a.run_mot_challenge:
        print()
        folders_main(a)
    return 0


if __name__ == "__main__":
    sys.exit(main())
