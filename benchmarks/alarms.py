"""Alarms on real footage: PETS 2009 S2L1 frames 1-300 with its calibration, at the rate it was
recorded at (7 fps), under a surveillance user's scene of two counting lines, a loitering zone,
``[stationary]`` (5 s within 0.5 m) and ``[speed]`` (2.5 m/s): examples/pets-s2l1-alarms.toml.

The true events are those the ground-truth tracks imply under the scene (``analyze
gt_mot15.txt``, rows marked ``consider = 0`` left out); each row of the table is ``track
--scene`` (no video) with its settings, scored by ``evaluate-events`` (tolerance 1 s) per event
type: F1 and ``TP/GT/Pred``. The walkers move at 0.5-1.6 m/s in the ground truth, so a speeding
alarm is always false: the last lines count the speeding alarms of the same tracks under a limit
of 2.5 m/s and of 2.0 m/s (the tracks file analysed again with that limit), and the fastest
speed any track reached beyond its uncertainty.

``--row NAME=KEY=VALUE,KEY=VALUE`` adds a row with those ``--set`` overrides (repeatable); the
first row is always the defaults.

Run: .venv/bin/python benchmarks/alarms.py [--data ../shared/data] [--row NAME=KEY=V,...]
         [--frames 300] [--keep DIR]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
import tomllib
from pathlib import Path

import tomli_w

from motiontrack.cli import main
from motiontrack.evaluate.events import evaluate_events
from motiontrack.io.events import read_events

# benchmarks/ is on sys.path when a script here runs
from _pets import add_data_argument, pets_video
from _rows import parse_row

SCENE = Path(__file__).resolve().parents[1] / "examples" / "pets-s2l1-alarms.toml"
#: the rate PETS 2009 was recorded at (the clip is stored at 10 fps)
FPS = 7.0
#: the event types of the scene, in the table's order
TYPES = ("line_cross", "zone_enter", "zone_exit", "loiter", "stationary_start",
         "stationary_end", "speeding")


def quiet(argv: list[str]) -> None:
    """``motiontrack ARGV`` in this process, its output swallowed; exit when it fails."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        code = main(argv)
    if code != 0:
        sys.exit(f"motiontrack {' '.join(argv)} exited with {code}:\n{out.getvalue()[-2000:]}")


def with_limit(scene: Path, limit: float, folder: Path) -> Path:
    """A copy of ``scene`` whose speed limit is ``limit`` m/s."""
    data = tomllib.loads(scene.read_text())
    data["speed"]["limit_mps"] = limit
    path = folder / f"scene-{limit:g}.toml"
    path.write_bytes(tomli_w.dumps(data).encode())
    return path


def speeding(tracks: Path, scene: Path, camera: Path, folder: Path) -> int:
    """Speeding alarms of a tracks file analysed under ``scene``."""
    quiet(["analyze", str(tracks), "--scene", str(scene), "--fps", str(FPS), "--camera",
           str(camera), "-o", str(folder), "--force"])
    return sum(e.type == "speeding" for e in read_events(folder / "events.jsonl").events)


def main_(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_data_argument(ap)
    ap.add_argument("--row", action="append", type=parse_row, default=[],
                    help="NAME=KEY=VALUE,...: a row with these --set overrides")
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--keep", type=Path, help="keep the runs in this folder")
    args = ap.parse_args(argv)
    video = pets_video(args.data)
    camera = video.parent / "View_001.xml"
    rows = [("defaults", []), *args.row]
    with tempfile.TemporaryDirectory(prefix="alarms_") as scratch:
        base = args.keep or Path(scratch)
        base.mkdir(parents=True, exist_ok=True)
        gt_dir = base / "gt"
        quiet(["analyze", str(video.parent / "gt_mot15.txt"), "--scene", str(SCENE), "--fps",
               str(FPS), "--camera", str(camera), "-o", str(gt_dir), "--force"])
        gt = [e for e in read_events(gt_dir / "events.jsonl").events
              if e.frame <= args.frames]
        slow = with_limit(SCENE, 2.0, base)
        results = []
        for k, (name, sets) in enumerate(rows):
            run = base / f"run-{k}"
            quiet(["track", str(video), "--scene", str(SCENE), "--camera", str(camera),
                   "--fps", str(FPS), "--max-frames", str(args.frames), "--no-video",
                   "-o", str(run), "--force", *[a for s in sets for a in ("--set", s)]])
            pred = read_events(run / "events.jsonl").events
            ev = evaluate_events(gt, pred, tolerance_s=1.0)
            at2 = speeding(run / "tracks.txt", slow, camera, base / f"slow-{k}")
            results.append((name, ev, at2))
            print(f"  {name}: {len(pred)} events", file=sys.stderr)
    print(f"PETS 2009 S2L1 frames 1-{args.frames} at {FPS:g} fps, {SCENE.name}; "
          "F1 (TP/GT/Pred), tolerance 1 s")
    print(f"{'event type':<18}" + "".join(f"{name[:22]:>24}" for name, _, _ in results))
    for t in TYPES:
        cells = []
        for _, ev, _ in results:
            s = ev.by_type.get(t)
            if s is None:
                cells.append("-")
                continue
            f1 = "-" if s.f1 is None else f"{s.f1:.3f}"
            cells.append(f"{f1} ({s.tp}/{s.gt}/{s.pred})")
        print(f"{t:<18}" + "".join(f"{c:>24}" for c in cells))
    print(f"{'all':<18}" + "".join(f"{ev.total.f1:>14.3f} ({ev.total.tp}/{ev.total.gt}/"
                                   f"{ev.total.pred})".rjust(24) for _, ev, _ in results))
    print(f"{'speeding at 2.0':<18}" + "".join(f"{at2:>24}" for _, _, at2 in results))
    return 0


if __name__ == "__main__":
    sys.exit(main_())
