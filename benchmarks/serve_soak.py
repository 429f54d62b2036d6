"""A day of video through ``motiontrack serve``: two synthetic cameras at accelerated playback.

Two looping cameras, ``synth:crossing`` and ``synth:runner`` (each with the scene file of
``motiontrack synth-events``: a line, zones, loitering), stated at ``--fps`` frames per second
(default 5, the rate event detection runs at on surveillance servers) and played ``speed = 1000``
times faster than that (as fast as the machine processes them). Every event keeps its evidence
with the defaults (annotated snapshot, object crop, a clip from 5 s before to 10 s after).
``serve`` runs with ``--rotate-s`` (a new segment every so many wall-clock seconds) and
``--keep-gb`` (the oldest segments go while all take more), until each camera has played
``--hours`` of its frame rate's time (``hours * 3600 * fps`` frames) or ``--max-minutes`` of wall
time have passed.

Every ``--sample`` seconds: the frames each camera has played (over its processes, should one be
restarted), the bytes under the output folder, the events in the store and the store's own
size, the resident memory (VmRSS) of the server and of each camera process, and the events of
the store whose snapshot is missing although their segment is still there. A run's table shows
them against the hours of video played.

Checks at the end (exit 1 when one fails):

- retention bounds the disk: over the second half of the run the output folder never takes more
  than ``--keep-gb`` plus what the cameras write between two retention checks (the server checks
  every ``CHECK_EVERY_S`` = 60 s; the segments being written are never removed);
- the store is bounded with it: the events it holds in the second half never exceed the most it
  held in the first half by more than half (removed segments take their events with them);
- no event without its snapshot: every event of the store, at every sample and after the
  server stopped, has its snapshot file unless its segment was removed;
- no camera fails: no camera process is started again by the server (seen as a new process
  id of the camera);
- memory is flat: the median RSS of the server and of each camera over the last quarter of the
  samples is at most 10 MB or 5% (the larger) above its median over the second quarter; the
  least-squares slope over the second half is printed beside it (MB per 24 h of video).

Run: .venv/bin/python benchmarks/serve_soak.py [--hours 24] [--fps 5] [--keep-gb 0.2]
         [--rotate-s 60] [--sample 10] [--max-minutes 90] [--dir DIR] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import httpx
import numpy as np

from motiontrack.io.event_store import STORE_NAME, EventStore

from memory import vm_rss_mb  # benchmarks/ is on sys.path when a script here runs

CAMERAS = ("crossing", "runner")
CHECK_EVERY_S = 60.0     # motiontrack.serve.retention.CHECK_EVERY_S


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def tree_bytes(root: Path) -> int:
    """Bytes of the files under ``root`` (files that go while they are counted are left out)."""
    total = 0
    for folder, _, files in os.walk(root):
        for name in files:
            try:
                total += os.stat(os.path.join(folder, name)).st_size
            except OSError:
                pass
    return total


@dataclass
class Sample:
    wall: float                       # seconds since the cameras ran
    hours: float                      # hours of video the slower camera has played
    frames: dict[str, int]
    disk_mb: float
    store_events: int
    store_mb: float
    missing: int                      # events whose snapshot is gone while their segment is not
    rss: dict[str, float] = field(default_factory=dict)   # "server", camera names


def store_state(out: Path) -> tuple[int, int]:
    """(events in the store, those of them without their snapshot although their segment is
    still there)."""
    if not (out / STORE_NAME).is_file():
        return 0, 0
    with EventStore(out, readonly=True) as store:
        rows = [(e.segment, e.snapshot) for e in store]
    missing = 0
    for segment, snapshot in rows:        # segment: CAMERA/FOLDER, snapshot: relative to out
        if snapshot is not None and (out / snapshot).is_file():
            continue
        if (out / str(segment)).is_dir():
            missing += 1
    return len(rows), missing


class Soak:
    """``motiontrack serve`` over the two cameras, sampled."""

    def __init__(self, root: Path, args: argparse.Namespace) -> None:
        self.root, self.args = root, args
        self.out = root / "out"
        lines = []
        for name in CAMERAS:
            source = f"synth:{name}?fps={args.fps:g}"
            subprocess.run([sys.executable, "-m", "motiontrack", "-q", "synth-events", source,
                            "-o", str(root / name), "--force"], check=True)
            lines.append(f'[[camera]]\nname = "{name}"\nsource = "{source}"\n'
                         f'scene = "{name}/scene.toml"\nloop = true\nspeed = 1000\n')
        (root / "cameras.toml").write_text("\n".join(lines))
        self.port = _free_port()
        env = {k: v for k, v in os.environ.items() if k != "MOTIONTRACK_TOKEN"}
        self.log = open(root / "serve.log", "w")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "motiontrack", "serve", str(root / "cameras.toml"),
             "--port", str(self.port), "--out", str(self.out), "--rotate-s",
             f"{args.rotate_s:g}", "--keep-gb", f"{args.keep_gb:g}"],
            cwd=root, stdout=self.log, stderr=subprocess.STDOUT, env=env)
        self.client = httpx.Client(base_url=f"http://127.0.0.1:{self.port}", timeout=30)
        #: frames of each camera process seen so far: (camera, pid) -> frames
        self.played: dict[tuple[str, int], int] = {}
        self.pids: dict[str, int] = {}

    def cameras(self) -> list[dict] | None:
        try:
            return self.client.get("/api/cameras").json()
        except httpx.TransportError:
            if self.proc.poll() is not None:
                raise SystemExit(f"serve exited; see {self.root / 'serve.log'}") from None
            return None

    def frames(self) -> dict[str, int]:
        for cam in self.cameras() or []:
            if cam.get("pid"):
                self.pids[cam["name"]] = cam["pid"]
                key = (cam["name"], cam["pid"])
                self.played[key] = max(self.played.get(key, 0), int(cam["frames"]))
        return {name: sum(n for (c, _), n in self.played.items() if c == name)
                for name in CAMERAS}

    def sample(self, t0: float) -> Sample:
        frames = self.frames()
        events, missing = store_state(self.out)
        store_mb = sum(p.stat().st_size for p in self.out.glob(f"{STORE_NAME}*")) / 1e6
        rss = {"server": vm_rss_mb(self.proc.pid) or 0.0}
        rss.update({name: vm_rss_mb(pid) or 0.0 for name, pid in self.pids.items()})
        return Sample(wall=time.monotonic() - t0,
                      hours=min(frames.values()) / self.args.fps / 3600.0, frames=frames,
                      disk_mb=tree_bytes(self.out) / 1e6, store_events=events,
                      store_mb=store_mb, missing=missing, rss=rss)

    def stop(self) -> int:
        self.proc.send_signal(signal.SIGTERM)
        code = self.proc.wait(120)
        self.client.close()
        self.log.close()
        return code


def slope_per_day(hours: np.ndarray, values: np.ndarray) -> float:
    """Least-squares slope of ``values`` over ``hours``, per 24 hours."""
    if len(hours) < 2 or np.ptp(hours) == 0:
        return 0.0
    return float(np.polyfit(hours, values, 1)[0] * 24.0)


def checks(samples: list[Sample], final_missing: int, args: argparse.Namespace) -> list[tuple]:
    """(what, measured, target, met) of each check of the docstring."""
    half = len(samples) // 2
    first, second = samples[:half], samples[half:]
    out = []
    # bytes the cameras write per wall second, from the first samples (before any removal)
    rate = max((s.disk_mb / s.wall for s in first if s.wall > 0), default=0.0)
    bound = args.keep_gb * 1000 + rate * 2 * CHECK_EVERY_S
    worst = max(s.disk_mb for s in second)
    out.append(("disk, second half: most MB", f"{worst:.0f}",
                f"<= {bound:.0f} (keep-gb + 2 checks' writing at {rate:.2f} MB/s)",
                worst <= bound))
    held = max(s.store_events for s in first)
    most = max(s.store_events for s in second)
    out.append(("store, second half: most events", str(most), f"<= 1.5 x {held} (first half)",
                most <= 1.5 * held))
    missing = max(s.missing for s in samples)
    out.append(("events without their snapshot", f"{missing} sampled, {final_missing} at the end",
                "0", missing == 0 and final_missing == 0))
    hours = np.array([s.hours for s in second])
    q = max(1, len(samples) // 4)
    for who in samples[-1].rss:
        rss = lambda part: np.array([s.rss.get(who, 0.0) for s in part])   # noqa: E731
        before, after = float(np.median(rss(samples[q:2 * q]))), float(np.median(rss(samples[-q:])))
        allowed = max(10.0, 0.05 * before)
        slope = slope_per_day(hours, rss(second))
        out.append((f"RSS {who}, median of the last quarter",
                    f"{before:.0f} -> {after:.0f} MB (slope {slope:+.1f} MB/24 h)",
                    f"at most {allowed:.0f} MB above the second quarter's",
                    after - before <= allowed))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hours", type=float, default=24.0, help="hours of video per camera")
    ap.add_argument("--fps", type=float, default=5.0, help="the cameras' stated frame rate")
    ap.add_argument("--keep-gb", type=float, default=0.2, help="serve --keep-gb")
    ap.add_argument("--rotate-s", type=float, default=60.0, help="serve --rotate-s")
    ap.add_argument("--sample", type=float, default=10.0, help="seconds between samples")
    ap.add_argument("--max-minutes", type=float, default=90.0, help="wall-time limit")
    ap.add_argument("--dir", help="work folder (default: a temporary one, removed at the end)")
    ap.add_argument("--json", metavar="FILE", help="also write the samples and checks as JSON")
    args = ap.parse_args()
    for flag in ("hours", "fps", "keep_gb", "rotate_s", "sample", "max_minutes"):
        if not getattr(args, flag) > 0:
            ap.error(f"--{flag.replace('_', '-')} must be positive")
    with tempfile.TemporaryDirectory(prefix="serve-soak-") as tmp:
        root = Path(args.dir) if args.dir else Path(tmp)
        root.mkdir(parents=True, exist_ok=True)
        return soak(root, args)


def soak(root: Path, args: argparse.Namespace) -> int:
    target = args.hours * 3600 * args.fps
    print(f"serve: {len(CAMERAS)} cameras at {args.fps:g} fps played unpaced, --rotate-s "
          f"{args.rotate_s:g} --keep-gb {args.keep_gb:g}; until {target:,.0f} frames each "
          f"({args.hours:g} h) or {args.max_minutes:g} min", flush=True)
    run = Soak(root, args)
    samples: list[Sample] = []
    try:
        end = time.monotonic() + 120
        while not (run.frames() and min(run.frames().values()) > 0):
            if time.monotonic() > end:
                raise SystemExit(f"the cameras did not start; see {root / 'serve.log'}")
            time.sleep(0.5)
        t0 = time.monotonic()
        print(f"{'wall s':>7}{'video h':>8}{'fps':>7}{'disk MB':>9}{'events':>8}{'db MB':>7}"
              f"{'missing':>8}  RSS MB (server, cameras)", flush=True)
        while True:
            time.sleep(args.sample)
            s = run.sample(t0)
            samples.append(s)
            fps = sum(s.frames.values()) / s.wall
            rss = ", ".join(f"{v:.0f}" for v in s.rss.values())
            print(f"{s.wall:7.0f}{s.hours:8.2f}{fps:7.0f}{s.disk_mb:9.1f}{s.store_events:8d}"
                  f"{s.store_mb:7.1f}{s.missing:8d}  {rss}", flush=True)
            if s.hours >= args.hours or s.wall >= args.max_minutes * 60:
                break
    finally:
        code = run.stop()
    final_events, final_missing = store_state(run.out)
    last = samples[-1]
    print(f"\n{last.hours:.2f} h of video per camera ({sum(last.frames.values()):,} frames) in "
          f"{last.wall / 60:.1f} min; serve exited {code}; the store holds {final_events} events")
    results = checks(samples, final_missing, args) if len(samples) >= 4 else []
    restarts = {name: len({pid for (c, pid) in run.played if c == name}) - 1 for name in CAMERAS}
    results.append(("camera processes started again (a camera that failed)",
                    ", ".join(f"{n} {k}" for n, k in restarts.items()), "0",
                    not any(restarts.values())))
    for what, measured, target_, met in results:
        print(f"  {'met ' if met else 'MISS'} {what}: {measured} (target {target_})")
    if args.json:
        Path(args.json).write_text(json.dumps({
            "args": vars(args), "samples": [s.__dict__ for s in samples],
            "checks": [dict(zip(("what", "measured", "target", "met"), r)) for r in results]},
            indent=1))
    reached = last.hours >= args.hours
    if not reached:
        print(f"  MISS {args.hours:g} h of video not reached within {args.max_minutes:g} min")
    return 0 if code == 0 and reached and all(r[3] for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
