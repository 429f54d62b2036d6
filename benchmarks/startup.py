"""Start-up: how long a command takes before it does any work, as a fresh process from its start
to its exit (interpreter start, imports, building the parser, printing).

Cases:
  python -c "import cv2"        the floor: every command that reads video pays it
  motiontrack --help            the top-level help
  motiontrack track --help      track's help, with its list of encodable codecs read from the
                                cached probe of this installation (motiontrack.io.codec_cache)
  track --help, codecs probed   the same with the cache emptied before each run: the first help
                                after installing (it imports OpenCV and PyAV and opens each encoder)
  import of the track path      python -c "import motiontrack.cli, motiontrack.run.jobs": what
                                `motiontrack track VIDEO` imports before its first frame

Each of --rounds rounds runs every case once, the order rotated by one each round, so a slow phase
of the machine hits every case alike. Per case: wall time and CPU time (user + sys, os.wait4) of
the process, median and range (min-max) over the rounds, and the median over the rounds of each
round's ratio to the same round's floor. Python's bytecode is cached (in a temporary
PYTHONPYCACHEPREFIX, filled by one warm-up run of each case), as in an installed package; the
codec list is cached in a temporary XDG_CACHE_HOME.

Run: .venv/bin/python benchmarks/startup.py [--rounds 7]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
from pathlib import Path

from _child import motiontrack_command, run_child  # benchmarks/ is on sys.path when a script here runs

#: wall-time target of the two help commands (seconds, median)
HELP_TARGET_S = 0.3


def cases() -> list[tuple[str, list[str]]]:
    mt = motiontrack_command()
    py = sys.executable
    return [('python -c "import cv2"', [py, "-c", "import cv2"]),
            ("motiontrack --help", [*mt, "--help"]),
            ("motiontrack track --help", [*mt, "track", "--help"]),
            ("track --help, codecs probed", [*mt, "track", "--help"]),
            ("import of the track path", [py, "-c", "import motiontrack.cli, motiontrack.run.jobs"])]


def _span(values: list[float], digits: int = 3) -> str:
    return (f"{statistics.median(values):.{digits}f} "
            f"[{min(values):.{digits}f}-{max(values):.{digits}f}]")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=7, help="runs of each case (default 7)")
    args = ap.parse_args()
    if args.rounds < 1:
        ap.error("--rounds must be at least 1")
    work = Path(tempfile.mkdtemp(prefix="motiontrack-startup-"))
    codecs = work / "cache"
    # the children inherit these: bytecode written and read as an installed package's is, and
    # the codec list cached in a folder of this run only
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    os.environ["PYTHONPYCACHEPREFIX"] = str(work / "bytecode")
    os.environ["XDG_CACHE_HOME"] = str(codecs)
    todo = cases()
    wall: dict[str, list[float]] = {name: [] for name, _ in todo}
    cpu: dict[str, list[float]] = {name: [] for name, _ in todo}
    floor = todo[0][0]
    try:
        for _, argv in todo:   # warm-up: bytecode compiled, the codec list probed and cached
            run_child(argv)
        for r in range(args.rounds):
            for name, argv in todo[r % len(todo):] + todo[:r % len(todo)]:
                if name.endswith("codecs probed"):
                    shutil.rmtree(codecs / "motiontrack", ignore_errors=True)
                run = run_child(argv)
                wall[name].append(run.wall_s)
                cpu[name].append(run.cpu_s)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"start-up, {args.rounds} rounds, cases interleaved; whole process, seconds: median "
          "[min-max]; x floor: median of each round's ratio to its floor run")
    print(f"{'case':<30}{'wall s':>22}{'CPU s':>22}{'wall x floor':>14}{'CPU x floor':>13}")
    for name, _ in todo:
        rw = [w / f for w, f in zip(wall[name], wall[floor])]
        rc = [c / f for c, f in zip(cpu[name], cpu[floor])]
        print(f"{name:<30}{_span(wall[name]):>22}{_span(cpu[name]):>22}"
              f"{statistics.median(rw):>14.2f}{statistics.median(rc):>13.2f}")
    for name in ("motiontrack --help", "motiontrack track --help"):
        m = statistics.median(wall[name])
        print(f"target: {name} < {HELP_TARGET_S} s wall (median): "
              f"{'met' if m < HELP_TARGET_S else 'NOT met'} ({m:.3f} s)")


if __name__ == "__main__":
    main()
