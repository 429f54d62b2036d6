"""Memory of a long `motiontrack track` run with its annotated video, seen from outside the process.

`motiontrack track "synth:SCENE?n_frames=N"` runs as a user runs it (annotated WebM video, tracks,
summary, and the scene's own ground truth scored at the end), its progress bar on a
pseudo-terminal so the frames done are known while it runs. Every --interval seconds the child's
resident memory is read from /proc/PID/status (VmRSS). Printed: RSS at every 10% of the frames,
the peak (ru_maxrss of the process, from os.wait4), and the slope of RSS over the second half of
the frames (least squares, MB per 1000 frames).

Targets: flat, |slope| <= 0.1 MB per 1000 frames (under 1 MB over the second half of 20,000
frames), and peak RSS < 300 MB.

Run: .venv/bin/python benchmarks/memory.py [--frames 20000] [--scene crowd] [--interval 1]
     [--json FILE]
"""

from __future__ import annotations

import argparse
import fcntl
import json
import os
import pty
import re
import struct
import subprocess
import sys
import tempfile
import termios
import threading
import time
from pathlib import Path

import numpy as np

from _child import motiontrack_command  # benchmarks/ is on sys.path when a script here runs

SLOPE_TARGET = 0.1      # MB per 1000 frames
PEAK_TARGET = 300.0     # MB
#: tqdm's counter "done/total [" on the progress bar
PROGRESS = re.compile(rb"(\d+)/(\d+) \[")


class Progress(threading.Thread):
    """Reads the child's progress bar from the pseudo-terminal (draining it, so the child never
    blocks on a full terminal) and keeps the last frame count seen."""

    def __init__(self, fd: int) -> None:
        super().__init__(daemon=True)
        self.fd = fd
        self.done = 0
        self.text = bytearray()   # the last few kB, for the message of a failed run

    def run(self) -> None:
        tail = b""
        while True:
            try:
                chunk = os.read(self.fd, 65536)
            except OSError:       # EIO: every writer of the terminal has closed it
                break
            if not chunk:
                break
            self.text = (self.text + chunk)[-8000:]
            counts = PROGRESS.findall(tail + chunk)
            if counts:
                self.done = int(counts[-1][0])
            tail = (tail + chunk)[-64:]


def vm_rss_mb(pid: int) -> float | None:
    """The resident memory of ``pid`` (MB), None once it has exited."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except (OSError, ValueError, IndexError):
        pass
    return None


def run_sampled(argv: list[str], interval: float) -> tuple[list[tuple[float, float, int]], float,
                                                              float, int, str]:
    """Run ``argv`` with its stderr on a pseudo-terminal; return its samples ``(seconds since the
    start, RSS MB, frames done)``, its wall time, peak RSS (MB), exit code and terminal output."""
    master, slave = pty.openpty()
    # a terminal 120 columns wide: tqdm sizes its bar to it
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=slave, stdin=subprocess.DEVNULL)
    os.close(slave)
    reader = Progress(master)
    reader.start()
    samples = []
    while True:
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            break
        rss = vm_rss_mb(proc.pid)
        if rss is not None:
            samples.append((time.perf_counter() - t0, rss, reader.done))
        time.sleep(interval)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    reader.join(timeout=5)
    os.close(master)
    return (samples, wall, usage.ru_maxrss / 1024.0, proc.returncode,
            reader.text.decode("utf-8", "replace"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=20000, help="frames of the scene (default 20000)")
    ap.add_argument("--scene", default="crowd", help="synthetic scene (`motiontrack list`; default "
                    "crowd: 5-8 people walking in, crossing and leaving)")
    ap.add_argument("--interval", type=float, default=1.0, help="seconds between RSS samples")
    ap.add_argument("--json", metavar="FILE", help="also write the samples and the results as JSON")
    args = ap.parse_args()
    if args.frames < 10:
        ap.error(f"--frames must be at least 10, got {args.frames}")
    if args.interval <= 0:
        ap.error(f"--interval must be positive, got {args.interval}")
    source = f"synth:{args.scene}?n_frames={args.frames}"
    with tempfile.TemporaryDirectory(prefix="memory-") as work:
        out = Path(work) / "out"
        argv = [*motiontrack_command(), "track", source, "-o", str(out)]
        print(f"{' '.join(argv[:-2])} -o OUT: RSS every {args.interval:g} s", flush=True)
        samples, wall, peak, code, text = run_sampled(argv, args.interval)
        if code != 0:
            sys.exit(f"motiontrack track exited with {code}:\n{text[-3000:]}")
        summary = json.loads((out / "summary.json").read_text())
        video = next((Path(p).name for k, p in summary["outputs"].items() if "video" in k), None)
    frames = int(summary["frames"])
    t, rss, done = (np.array(c, float) for c in zip(*samples)) if samples else (np.zeros(0),) * 3
    from_bar = bool(done.any())
    if not from_bar:
        # no progress bar read: frames done estimated from the time elapsed
        done = frames * t / wall
    marks = []
    print(f"{'progress':>9}{'frames':>8}{'seconds':>9}{'RSS MB':>9}")
    for pct in range(10, 101, 10):
        reached = np.flatnonzero(done >= frames * pct / 100)
        # the last sample stands for 100% when the run ended between two samples
        k = int(reached[0]) if reached.size else (len(t) - 1 if pct == 100 and len(t) else None)
        if k is None:
            continue
        marks.append({"percent": pct, "frames": int(done[k]), "seconds": float(t[k]),
                      "rss_mb": float(rss[k])})
        print(f"{pct:>8}%{int(done[k]):>8}{t[k]:>9.1f}{rss[k]:>9.1f}")
    half = done >= frames / 2
    slope = (float(np.polyfit(done[half], rss[half], 1)[0] * 1000)
             if half.sum() >= 3 and np.ptp(done[half]) > 0 else None)
    flat = slope is not None and abs(slope) <= SLOPE_TARGET
    print(f"{frames} frames in {wall:.1f} s ({frames / wall:.1f} fps, {summary['tracks']} track ids, "
          f"{video or 'no video'}), {len(t)} samples, frames done from the "
          f"{'progress bar' if from_bar else 'time elapsed'}")
    print(f"peak RSS {peak:.1f} MB (target < {PEAK_TARGET:.0f} MB: "
          f"{'met' if peak < PEAK_TARGET else 'MISSED'})")
    print("RSS slope over the second half: "
          + (f"{slope:+.3f} MB per 1000 frames" if slope is not None else "n/a (fewer than 3 samples)")
          + f" (target flat, |slope| <= {SLOPE_TARGET} MB per 1000 frames: "
          + f"{'met' if flat else 'MISSED'})")
    if args.json:
        Path(args.json).write_text(json.dumps({
            "source": source, "frames": frames, "wall_s": wall, "tracks": summary["tracks"],
            "peak_rss_mb": peak, "slope_mb_per_1000_frames": slope,
            "frames_done_from": "progress bar" if from_bar else "time elapsed", "marks": marks,
            "samples": [{"seconds": a, "rss_mb": b, "frames": int(c)} for a, b, c in zip(t, rss, done)],
            "targets": {"peak_below_300_mb": peak < PEAK_TARGET, "flat": flat},
        }, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
