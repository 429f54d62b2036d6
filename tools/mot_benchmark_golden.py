#!/usr/bin/env python3
"""A multi-tracker MOTChallenge benchmark on mot17-mini, scored by TrackEval's own
``scripts/run_mot_challenge.py``, dumped as golden JSON.

TrackEval lives in its own virtual environment (see ``tools/trackeval_golden.py``); its PyPI
wheel does not ship the ``scripts/`` folder, the sdist does::

    python3 -m venv /tmp/te-venv && /tmp/te-venv/bin/pip install trackeval==1.3.0
    /tmp/te-venv/bin/pip download --no-binary :all: --no-deps trackeval==1.3.0 -d /tmp/te-sdist
    tar xzf /tmp/te-sdist/trackeval-1.3.0.tar.gz -C /tmp/te-sdist
    python3 tools/mot_benchmark_golden.py --split ../shared/data/mot17-mini/train \\
        --trackeval-python /tmp/te-venv/bin/python \\
        --run-mot-challenge /tmp/te-sdist/trackeval-1.3.0/scripts/run_mot_challenge.py \\
        --out tests/golden/benchmark/mot17-mini-trackers.json

The trackers are made from the split's own files, deterministically (standard library only, so
the tests rebuild the same folder with :func:`make_trackers`):

* ``perturbed-a``, ``perturbed-b``: ``trackeval_golden.perturb_gt`` of every gt file (drops,
  jitter, boxes pushed below IoU 0.5, an id swap, a restarted id, false positives);
* ``det-linked``: the public detections (``det/det.txt``) of the annotated frames, linked from
  frame to frame by greedy IoU (>= 0.3), a new id for every unmatched detection.

``run_mot_challenge.py`` runs with its defaults (MOT17, HOTA + CLEAR + Identity, threshold 0.5)
and ``--GT_FOLDER SPLIT --TRACKERS_FOLDER T --SKIP_SPLIT_FOL True --SEQ_INFO <every sequence>``;
its ``pedestrian_detailed.csv`` of every tracker is read back (full precision) into
``{"trackers": {tracker: {sequence | "COMBINED": {field: value}}}}`` with TrackEval's column
names (``HOTA___AUC`` is the mean over the 19 alphas).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from trackeval_golden import perturb_gt  # noqa: E402

TRACKERS = ("det-linked", "perturbed-a", "perturbed-b")
#: the detailed-CSV columns kept in the golden file
FIELDS = ("HOTA___AUC", "DetA___AUC", "AssA___AUC", "LocA___AUC", "DetRe___AUC", "DetPr___AUC",
          "AssRe___AUC", "AssPr___AUC", "HOTA(0)", "LocA(0)", "MOTA", "MOTP", "MODA", "sMOTA",
          "CLR_Re", "CLR_Pr", "CLR_TP", "CLR_FN", "CLR_FP", "IDSW", "MT", "PT", "ML", "Frag",
          "IDF1", "IDR", "IDP", "IDTP", "IDFN", "IDFP")


def _iou(a, b) -> float:
    ix = min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0])
    iy = min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1])
    inter = max(ix, 0.0) * max(iy, 0.0)
    union = a[2] * a[3] + b[2] * b[3] - inter
    return inter / union if union > 0 else 0.0


def link_detections(det_path: Path, last_frame: int) -> str:
    """Greedy IoU linking of the detections of frames 1..last_frame (a tracker with no motion
    model): each frame's detections take the ids of the previous frame's boxes, best IoU first."""
    by_frame: dict[int, list[list[float]]] = {}
    for line in det_path.read_text().split():
        r = [float(t) for t in line.split(",")]
        if 1 <= int(r[0]) <= last_frame:
            by_frame.setdefault(int(r[0]), []).append(r)
    out, prev, next_id = [], [], 1
    for f in sorted(by_frame):
        dets = by_frame[f]
        pairs = sorted(((_iou(d[2:6], p[1]), i, j) for i, d in enumerate(dets)
                        for j, p in enumerate(prev)), reverse=True)
        ids: dict[int, int] = {}
        used: set[int] = set()
        for iou, i, j in pairs:
            if iou < 0.3:
                break
            if i not in ids and j not in used:
                ids[i] = prev[j][0]
                used.add(j)
        cur = []
        for i, d in enumerate(dets):
            if i not in ids:
                ids[i] = next_id
                next_id += 1
            cur.append((ids[i], d[2:6]))
            out.append(f"{f},{ids[i]},{d[2]:.2f},{d[3]:.2f},{d[4]:.2f},{d[5]:.2f},{d[6]:g},"
                       "-1,-1,-1\n")
        prev = cur
    return "".join(out)


def _last_gt_frame(gt: Path) -> int:
    return max((int(float(line.split(",")[0])) for line in gt.read_text().split()), default=0)


def make_trackers(split: Path, out: Path) -> list[str]:
    """Write ``out/<tracker>/data/<seq>.txt`` for every sequence of ``split``; the sequence names."""
    seqs = sorted(d.name for d in split.iterdir() if (d / "gt" / "gt.txt").is_file())
    for t in TRACKERS:
        (out / t / "data").mkdir(parents=True, exist_ok=True)
    for k, s in enumerate(seqs):
        gt = split / s / "gt" / "gt.txt"
        data = {"perturbed-a": perturb_gt(gt, seed=100 + k),
                "perturbed-b": perturb_gt(gt, seed=200 + k),
                "det-linked": link_detections(split / s / "det" / "det.txt", _last_gt_frame(gt))}
        for t, text in data.items():
            (out / t / "data" / f"{s}.txt").write_text(text)
    return seqs


def read_detailed(path: Path) -> dict[str, dict[str, float]]:
    """TrackEval's ``<class>_detailed.csv``: {sequence | "COMBINED": {column: number}}."""
    with path.open(newline="") as fh:
        return {row["seq"]: {k: float(v) for k, v in row.items() if k != "seq"}
                for row in csv.DictReader(fh)}


def run_mot_challenge_cmd(python: str, script: str, split: Path, trackers: Path,
                          seqs: list[str]) -> list[str]:
    """The ``run_mot_challenge.py`` command line for a split folder and a trackers folder."""
    return [python, script, "--GT_FOLDER", str(split), "--TRACKERS_FOLDER", str(trackers),
            "--SKIP_SPLIT_FOL", "True", "--SEQ_INFO", *seqs]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--split", type=Path, required=True)
    ap.add_argument("--trackeval-python", required=True)
    ap.add_argument("--run-mot-challenge", required=True)
    ap.add_argument("--out", type=Path, required=True)
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="te-bench-") as tmp:
        trackers = Path(tmp) / "trackers"
        seqs = make_trackers(a.split, trackers)
        subprocess.run(run_mot_challenge_cmd(a.trackeval_python, a.run_mot_challenge, a.split,
                                             trackers, seqs),
                       check=True, stdout=subprocess.DEVNULL)
        res = {}
        for t in TRACKERS:
            rows = read_detailed(trackers / t / "pedestrian_detailed.csv")
            res[t] = {seq: {k: row[k] for k in FIELDS} for seq, row in rows.items()}
    version = subprocess.run([a.trackeval_python, "-c", "import trackeval; print(getattr("
                              "trackeval, '__version__', '?'))"],
                             check=True, capture_output=True, text=True).stdout.strip()
    doc = {"trackeval_version": version, "script": "scripts/run_mot_challenge.py",
           "split": "data:mot17-mini/train", "sequences": seqs, "trackers": res}
    tmp_out = a.out.with_suffix(".json.part")
    tmp_out.write_text(json.dumps(doc, indent=1) + "\n")
    os.replace(tmp_out, a.out)
    print(f"wrote {a.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
