"""Check that a change leaves the tracks byte-identical: ``motiontrack track`` on fixed inputs,
the SHA-256 of the ten MOTChallenge columns of every ``tracks.txt`` compared with a recorded set.

Cases: PETS 2009 S2L1 frames 1-300 with the defaults and with ``--preset people``, the synthetic
``crossing`` and ``column`` scenes, and PETS tracked from seeded jittered ground-truth detections
(``--detections``) by the motion-blob tracker and by the detections preset. Every case runs the installed command in a process of its own, as a user
runs it.

Run:
    .venv/bin/python tools/identical_tracks.py --record tools/track_hashes.json   # before
    .venv/bin/python tools/identical_tracks.py --check tools/track_hashes.json    # after

The hashes hold for one OpenCV build (the KNN background model's arithmetic); the file records
the version, and ``--check`` says so when it differs.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

REPO = Path(__file__).resolve().parents[1]


def _data(arg: str | None) -> Path:
    return Path(arg or os.environ.get("MOTIONTRACK_DATA", REPO.parent / "shared" / "data")).resolve()


def _detections(gt: Path, out: Path, seed: int = 0) -> Path:
    """Ground-truth boxes of the people (consider = 1) with 5 % jitter of the box height and 10 %
    of them dropped, as MOTChallenge det rows (id -1)."""
    rows = np.loadtxt(gt, delimiter=",", ndmin=2)
    rows = rows[rows[:, 6] == 1]
    rng = np.random.default_rng(seed)
    rows = rows[rng.random(len(rows)) >= 0.1]
    h = rows[:, 5:6]
    box = rows[:, 2:6] + rng.normal(0.0, 0.05, (len(rows), 4)) * h
    box[:, 2:] = np.maximum(box[:, 2:], 2.0)
    lines = [f"{int(f)},-1,{x:.2f},{y:.2f},{w:.2f},{hh:.2f},1,-1,-1,-1"
             for f, (x, y, w, hh) in zip(rows[:, 0], box)]
    out.write_text("\n".join(lines) + "\n")
    return out


def cases(data: Path, tmp: Path) -> dict[str, list[str]]:
    pets = data / "pets09-s2l1"
    video = str(pets / "video.avi")
    det = _detections(pets / "gt_mot15.txt", tmp / "det.txt")
    return {
        "pets-default": [video],
        "pets-people": [video, "--preset", "people"],
        "synth-crossing": ["synth:crossing"],
        "synth-column": ["synth:column"],
        # the motion-blob tracker on detections, with its own defaults (--detections alone
        # runs the detections preset)
        "pets-detections": [video, "--detections", str(det), *_sets(
            "tracker.method=kalman", "tracker.confirm_hits=5", "tracker.max_lost_s=2",
            "tracker.fill_gaps_s=1")],
        "pets-detections-preset": [video, "--detections", str(det)],
    }


def _sets(*overrides: str) -> list[str]:
    return [a for o in overrides for a in ("--set", o)]


def run_case(name: str, args: list[str], tmp: Path) -> str:
    out = tmp / name
    cmd = [sys.executable, "-m", "motiontrack", "-q", "track", *args, "--no-video", "-o", str(out),
           "--force"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"{name}: {' '.join(cmd)} exited {proc.returncode}:\n{proc.stderr}")
    # the ten MOTChallenge columns: the tracks themselves; the class column after them is the
    # classifier's (tests/classify), so a change of the classes alone is not a change of tracks
    rows = (out / "tracks.txt").read_text().splitlines()
    return hashlib.sha256("".join(",".join(r.split(",")[:10]) + "\n" for r in rows).encode()
                          ).hexdigest()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--record", metavar="JSON", help="write the hashes to JSON")
    mode.add_argument("--check", metavar="JSON", help="compare the hashes with JSON")
    ap.add_argument("--data", help="the shared data folder (default $MOTIONTRACK_DATA or "
                                   "../shared/data)")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        hashes = {name: run_case(name, a, tmp) for name, a in cases(_data(args.data), tmp).items()}
    if args.record:
        Path(args.record).write_text(json.dumps({"opencv": cv2.__version__, "tracks": hashes},
                                                indent=2) + "\n")
        print(f"recorded {len(hashes)} cases in {args.record}")
        return 0
    ref = json.loads(Path(args.check).read_text())
    if ref.get("opencv") != cv2.__version__:
        print(f"note: recorded with OpenCV {ref.get('opencv')}, running {cv2.__version__}")
    bad = [n for n, h in hashes.items() if ref["tracks"].get(n) != h]
    for n in hashes:
        print(f"{n:16s} {'identical' if n not in bad else 'DIFFERENT'}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
