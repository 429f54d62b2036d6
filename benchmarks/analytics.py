"""What scene analytics add to ``motiontrack track``: the PETS 2009 S2L1 clip tracked without and
with a scene of 10 lines and 10 zones (no annotated video), side by side.

Each round runs both jobs (in alternating order, so that a slow phase of the machine hits both);
the table prints each one's median and range over the rounds and the ratio of the medians. The
job with a scene writes everything ``track --scene`` writes: events.jsonl, events.db,
counts.csv, heatmap.png and the analytics in summary.json, first without the events' snapshots
and clips (``[evidence]`` off), then with them (the default).

It also times the analytics engine alone (``Analytics.step``) on the tracks of the run, per
frame, and with 10 tracks per frame on synthetic paths, which is what to profile when the ratio
grows.

Run: .venv/bin/python benchmarks/analytics.py [--data ../shared/data] [--frames 300] [--repeat 5]
"""

from __future__ import annotations

import statistics
import tempfile
import time
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np

from motiontrack.analytics import Analytics, parse_scene
from motiontrack.config import PipelineConfig
from motiontrack.io.mot import read_mot
from motiontrack.run import track_job

from _pets import pets_args  # benchmarks/ is on sys.path when a script here runs


def scene_toml(n_lines: int = 10, n_zones: int = 10) -> str:
    """Lines and zones spread over the PETS walkway (768 x 576): vertical lines across the
    road every 60 px, and boxes along it."""
    out = []
    for i in range(n_lines):
        x = 60 + 65 * i
        out.append(f'[[line]]\nname = "line{i + 1}"\npoints = [[{x}, 150], [{x + 20}, 450]]\n')
    for k in range(n_zones):
        x0, y0 = 30 + 70 * k, 180 + (k % 3) * 60
        out.append(f'[[zone]]\nname = "zone{k + 1}"\n'
                   f'polygon = [[{x0}, {y0}], [{x0 + 90}, {y0}], [{x0 + 110}, {y0 + 120}], '
                   f'[{x0 - 10}, {y0 + 120}]]\nloiter_s = 5\n')
    return "\n".join(out)


def run_track(video: Path, cfg: PipelineConfig, scene: Path | None) -> tuple[float, float]:
    """Wall-clock and CPU seconds (all threads of the process) of one ``track`` job, outputs in
    a temporary folder. CPU time is the steadier of the two on a machine doing other work."""
    with tempfile.TemporaryDirectory() as d:
        job = track_job(str(video), cfg, d, force=True, scene=scene)
        t, c = time.perf_counter(), time.process_time()
        job.run()
        return time.perf_counter() - t, time.process_time() - c


def engine_ms_per_frame(scene_doc: dict, frames: list[tuple[np.ndarray, np.ndarray]],
                        fps: float, repeat: int = 3) -> float:
    """Milliseconds per frame of ``Analytics.step`` alone over ``frames`` (fastest run)."""
    best = float("inf")
    for _ in range(repeat):
        an = Analytics(parse_scene(scene_doc), fps)
        t = time.perf_counter()
        for f, (ids, boxes) in enumerate(frames, start=1):
            an.step(f, ids, boxes)
        best = min(best, (time.perf_counter() - t) / len(frames) * 1e3)
    return best


def synthetic_frames(n_frames: int, n_tracks: int = 10) -> list[tuple[np.ndarray, np.ndarray]]:
    """``n_tracks`` people walking straight across the frame and back (seeded)."""
    rng = np.random.default_rng(0)
    start = rng.uniform([50, 150], [700, 450], (n_tracks, 2))
    vel = rng.normal(0, 4, (n_tracks, 2))
    ids = np.arange(1, n_tracks + 1)
    out = []
    for f in range(n_frames):
        p = start + vel * (f % 100 if (f // 100) % 2 == 0 else 100 - f % 100)
        out.append((ids, np.column_stack([p[:, 0] - 15, p[:, 1] - 80, np.full(n_tracks, 30),
                                          np.full(n_tracks, 80)])))
    return out


def _row(name: str, runs: list[tuple[float, float]]) -> str:
    out = f"{name:<34}"
    for xs in zip(*runs):
        out += f" {statistics.median(xs):7.3f} s ({min(xs):.3f} - {max(xs):.3f})"
    return out


def _ratio(what: str, plain: list[float], scened: list[float], added: str = "analytics") -> str:
    ratio = statistics.median(scened) / statistics.median(plain)
    return f"{what} ratio {ratio:.3f}: {added} add {100 * (ratio - 1):+.1f} %"


#: the scene's events without snapshots and clips (the [evidence] table)
NO_EVIDENCE = "\n[evidence]\nsnapshot = false\nclip_s = [0, 0]\n"


def main() -> None:
    args, video, _ = pets_args(__doc__, repeat=5)
    cfg = PipelineConfig()
    cfg = replace(cfg, source=replace(cfg.source, max_frames=args.frames),
                  output=replace(cfg.output, video=False))
    toml = scene_toml()
    with tempfile.TemporaryDirectory() as d:
        scene, bare = Path(d) / "scene.toml", Path(d) / "bare.toml"
        scene.write_text(toml)
        bare.write_text(toml + NO_EVIDENCE)
        run_track(video, cfg, None)   # warm-up: imports, caches, the file in the page cache
        plain, scened, evidenced = [], [], []
        runs = [(None, plain), (bare, scened), (scene, evidenced)]
        for r in range(args.repeat):
            for s, acc in (runs if r % 2 == 0 else runs[::-1]):
                acc.append(run_track(video, cfg, s))
        # the engine alone, on the tracks the pipeline reports
        with tempfile.TemporaryDirectory() as d2:
            job = track_job(str(video), cfg, d2, force=True)
            summary = job.run()
            tracks = read_mot(Path(d2) / "tracks.txt")
    doc = tomllib.loads(toml)
    by_frame = tracks.by_frame()
    frames = [(tracks.ids[by_frame[f]], tracks.boxes[by_frame[f]]) if f in by_frame
              else (np.zeros(0, np.int64), np.zeros((0, 4))) for f in range(1, summary.frames + 1)]
    fps = summary.source_fps or 25.0
    per_frame = statistics.median(c for _, c in plain) / summary.frames * 1e3
    print(f"PETS S2L1, {summary.frames} frames, no video; {args.repeat} interleaved rounds, "
          "median (range)")
    print(f"{'':<34} {'wall clock':<25} {'CPU (all threads)':<25}")
    print(_row("track", plain))
    print(_row("track --scene (10 lines, 10 zones)", scened))
    print(_row("  + snapshots and clips", evidenced))
    print(_ratio("wall-clock", [w for w, _ in plain], [w for w, _ in scened]))
    print(_ratio("CPU", [c for _, c in plain], [c for _, c in scened])
          + f" (track alone {per_frame:.1f} ms CPU per frame)")
    print(_ratio("CPU with evidence", [c for _, c in plain], [c for _, c in evidenced],
                 "analytics and evidence"))
    n_tracks = len(tracks) / max(1, summary.frames)
    print(f"engine alone on the run's tracks ({n_tracks:.1f} per frame): "
          f"{engine_ms_per_frame(doc, frames, fps):.3f} ms/frame")
    print("engine alone, 10 tracks per frame: "
          f"{engine_ms_per_frame(doc, synthetic_frames(summary.frames), fps):.3f} ms/frame")


if __name__ == "__main__":
    main()
