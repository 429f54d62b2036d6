"""Throughput and accuracy on the PETS 2009 S2L1 clip: whole processes side by side, or the
stages in one process (--in-process).

Whole-process rows (the default): each row is a fresh process timed from its start to its exit,
as a user who types the command pays for it (interpreter start, imports, decoding, writing):
  decode only          — a tiny script reading every frame with cv2.VideoCapture (the floor)
  motion stage alone   — a script running what every default run does first, in one thread:
                         decoding, preprocessing, the KNN model and the mask clean-up
                         (``Pipeline.motion``), no regions, tracking or outputs. Its CPU time
                         over the tutorial's bounds what `track --no-video` can reach: the
                         pipeline does this work and more, on the same two cores
  tutorial             — benchmarks/tutorial.py, the classic OpenCV tutorial (below), writing its
                         boxes to a MOT file
  tutorial + video     — the same drawing its boxes and writing them with cv2.VideoWriter, once per
                         codec of --tutorial-fourccs (motiontrack's default VP8 and OpenCV's fast
                         ones); the fastest is the tutorial the annotated-video rows are held to
  track                — `motiontrack track VIDEO` (annotated video, the default) and
                         `--no-video`, then both with `--preset people`
Each of --rounds rounds runs every row once, the row order rotated by one each round, so a slow
phase of the machine hits every row alike. Per row: median and range (min-max) over the rounds of
wall time, fps (frames / wall), CPU time (user + sys) and peak RSS of the process (os.wait4);
speed ratios are each round's ratio to the same round's tutorial run, their median and range.
Accuracy is scored once, on the first round's outputs. The targets met are printed; --json FILE
writes every run.

In-process rows (--in-process):
  decode only        — cv2.VideoCapture.read() of every frame
  baseline           — the classic tutorial approach: gray + 5x5 Gaussian blur, MOG2 (history 500,
                       varThreshold 16, shadows on), threshold at 254, one 3x3 erosion, three 3x3
                       dilations, external contours with area >= 500 px, no identities
  motion mask only   — our default preprocessing + motion detector + mask clean-up (no regions)
  detector only      — the pipeline's own detection stage, ``Pipeline.detect``: the motion mask and
                       its regions, i.e. the boxes the tracker consumes (the part that
                       ``--detections det.txt`` replaces); no tracker. The "overhead" is what
                       tracking and the pipeline's plumbing add on top of it; the overhead on top
                       of the motion mask alone (regions included) is printed too
  pipeline (tracks)  — the full default pipeline, tracks only (no video)
  pipeline (--preset fast) — the same with the smaller KNN model of the ``fast`` preset
  pipeline (+video)  — the same writing the annotated WebM video
The in-process rows decode 300 frames unless --frames says otherwise; they keep the fastest of
the rounds (every other round in reverse order).

Accuracy: CLEAR-MOT, Identity and HOTA at IoU 0.5 against gt_mot15.txt (rows with consider = 0
are ignore regions). The tutorial has no identities: each box gets its own id, so only its recall
and precision compare.

Run: .venv/bin/python benchmarks/throughput.py [--data ../shared/data] [--frames N] [--rounds 5]
     [--json FILE] [--tutorial-fourccs VP80,mp4v,MJPG,XVID] [--in-process]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from motiontrack.config import PipelineConfig, load_config
from motiontrack.evaluate.mot import evaluate_tracking
from motiontrack.io.mot import read_mot
from motiontrack.motion import create_detector
from motiontrack.motion.cleanup import clean_mask
from motiontrack.pipeline import Pipeline, run
from motiontrack.run import track_job
from motiontrack.preprocess import preprocess
from motiontrack.types import Annotations, Frame

# benchmarks/ is on sys.path when a script here runs
import tutorial
from _child import ChildRun, cache_bytecode, motiontrack_command, run_child
from _pets import add_data_argument, pets_video


def decode_only(video: Path, n: int) -> tuple[float, None]:
    cap = cv2.VideoCapture(str(video))
    t = time.perf_counter()
    k = 0
    while k < n and cap.read()[0]:
        k += 1
    return k / (time.perf_counter() - t), None


def baseline(video: Path, n: int) -> tuple[float, Annotations]:
    """The tutorial approach, as the tutorial describes it (frames are decoded inside the timing)."""
    cap = cv2.VideoCapture(str(video))
    sub = tutorial.new_subtractor()
    rows = []
    t = time.perf_counter()
    k = 0
    next_id = 1
    while k < n:
        ok, frame = cap.read()
        if not ok:
            break
        for x, y, w, h in tutorial.detect(frame, sub):
            rows.append((k + 1, next_id, x, y, w, h))
            next_id += 1
        k += 1
    fps = k / (time.perf_counter() - t)
    a = np.array(rows, float).reshape(-1, 6)
    return fps, Annotations.from_columns(a[:, 0], a[:, 1], a[:, 2:6])


def _fps(cap: cv2.VideoCapture, n: int, step) -> float:
    """Frames per second of ``step(k, image)`` over the first ``n`` frames of ``cap``, decoding
    in the same thread (inside the timing)."""
    t = time.perf_counter()
    k = 0
    while k < n:
        ok, image = cap.read()
        if not ok:
            break
        step(k, image)
        k += 1
    return k / (time.perf_counter() - t)


def mask_only(video: Path, n: int, cfg: PipelineConfig) -> tuple[float, None]:
    det = create_detector(cfg.motion)
    return _fps(cv2.VideoCapture(str(video)), n, lambda k, image: clean_mask(
        det.apply(preprocess(image, cfg.preprocess)), cfg.cleanup)), None


def detector_only(video: Path, n: int, cfg: PipelineConfig) -> tuple[float, None]:
    """``Pipeline.detect`` on every frame (mask and regions)."""
    cap = cv2.VideoCapture(str(video))
    size = (int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))
    fps = cap.get(cv2.CAP_PROP_FPS) or 25.0
    pipe = Pipeline(cfg, size, None, fps)
    return _fps(cap, n, lambda k, image: pipe.detect(
        Frame(index=k, timestamp=k / fps, image=image), k)), None


def pipeline_tracks(video: Path, n: int, cfg: PipelineConfig) -> tuple[float, Annotations]:
    from dataclasses import replace

    cfg = replace(cfg, source=replace(cfg.source, max_frames=n))
    rows = []
    t = time.perf_counter()
    k = 0
    for res in run(str(video), cfg):
        for tr in res.tracks:
            rows.append((res.index + 1, tr.id, *tr.box.as_array()))
        k += 1
    fps = k / (time.perf_counter() - t)
    a = np.array(rows, float).reshape(-1, 6)
    return fps, Annotations.from_columns(a[:, 0], a[:, 1], a[:, 2:6])


def pipeline_video(video: Path, n: int, cfg: PipelineConfig) -> tuple[float, None]:
    from dataclasses import replace

    cfg = replace(cfg, source=replace(cfg.source, max_frames=n))
    with tempfile.TemporaryDirectory() as d:
        job = track_job(str(video), cfg, d, force=True)
        t = time.perf_counter()
        s = job.run()
        return s.frames / (time.perf_counter() - t), None


def score(gt: Annotations, pred: Annotations | None, n: int) -> dict[str, float] | None:
    if pred is None:
        return None
    gt = gt.select(gt.frames <= n)
    r = evaluate_tracking(gt, pred, metrics=("clear", "identity", "hota"), ignore_zero_marked=True)
    return {k: r[k] for k in ("recall", "precision", "MOTA", "IDF1", "HOTA")}


def in_process(args: argparse.Namespace, video: Path, gt: Annotations) -> None:
    """The stages side by side in this process (``--in-process``)."""
    cfg = PipelineConfig()
    fast = load_config(None, preset="fast")
    n = args.frames or 300

    # Runs are interleaved (one round = one run of every row, --rounds rounds) so a slow phase of
    # the machine hits the baseline and the pipeline alike; each row keeps its fastest run.
    timed = [
        ("decode only", decode_only, (video, n)),
        ("baseline (tutorial)", baseline, (video, n)),
        ("motion mask only", mask_only, (video, n, cfg)),
        ("detector only", detector_only, (video, n, cfg)),
        ("pipeline (tracks)", pipeline_tracks, (video, n, cfg)),
        ("pipeline (--preset fast)", pipeline_tracks, (video, n, fast)),
    ]
    runs: dict[str, list] = {name: [] for name, _, _ in timed}
    for k in range(args.rounds):
        # every other round runs the rows in reverse order, so a drift of the machine's speed
        # within a round favours neither the baseline nor the pipeline
        for name, fn, a in (timed if k % 2 == 0 else timed[::-1]):
            runs[name].append(fn(*a))
    # the ratio of each round's pipeline run to the same round's baseline run: robust to a
    # machine whose speed changes between rounds (shared virtual machines)
    def round_ratios(row: str) -> list[float]:
        return sorted(p[0] / b[0] for p, b in zip(runs[row], runs["baseline (tutorial)"]))

    ratios = round_ratios("pipeline (tracks)")
    fast_ratios = round_ratios("pipeline (--preset fast)")
    rows = [(name, max(r[0] for r in runs[name]), runs[name][0][1]) for name, _, _ in timed]
    rows.append(("pipeline (+video)", *pipeline_video(video, n, cfg)))
    base_fps = rows[1][1]
    mask_fps, det_fps, pipe_fps = rows[2][1], rows[3][1], rows[4][1]
    print(f"PETS09-S2L1 View 1, {n} frames of 768x576, one process, cv2 threads = "
          f"{cv2.getNumThreads()}, best of {args.rounds} interleaved rounds (annotated video: one run)")
    print(f"{'run':<26}{'fps':>8}{'x base':>8}  {'recall':>7}{'prec':>7}{'MOTA':>7}{'IDF1':>7}{'HOTA':>7}")
    for name, fps, pred in rows:
        s = score(gt, pred, n)
        acc = ("  " + "".join(f"{s[k]:>7.3f}" for k in ("recall", "precision", "MOTA", "IDF1", "HOTA"))
               if s else "")
        print(f"{name:<26}{fps:>8.1f}{fps / base_fps:>8.2f}{acc}")
    print(f"pipeline overhead on top of its own detector (mask + regions): "
          f"{(det_fps / pipe_fps - 1) * 100:.0f}% (target <= 20%)")
    print(f"pipeline overhead on top of the motion mask alone (regions counted as overhead): "
          f"{(mask_fps / pipe_fps - 1) * 100:.0f}%")
    # the same comparison in CPU time (all threads), which the machine's load disturbs less
    cpu = []
    for fn in (mask_only, detector_only, pipeline_tracks):
        c0 = time.process_time()
        fn(video, n, cfg)
        cpu.append((time.process_time() - c0) / n * 1e3)
    print(f"CPU time per frame: motion mask {cpu[0]:.2f} ms, detector {cpu[1]:.2f} ms, pipeline "
          f"{cpu[2]:.2f} ms (+{(cpu[2] / cpu[1] - 1) * 100:.0f}% on the detector)")
    print(f"pipeline (tracks) vs baseline: {pipe_fps / base_fps:.2f}x best against best; "
          f"{float(np.median(ratios)):.2f}x median of the {len(ratios)} rounds' ratios "
          f"(range {ratios[0]:.2f}-{ratios[-1]:.2f}) (target >= 1.5x)")
    print(f"--preset fast vs baseline: {float(np.median(fast_ratios)):.2f}x median of the rounds' "
          f"ratios (range {fast_ratios[0]:.2f}-{fast_ratios[-1]:.2f})")



# --- whole-process rows ----------------------------------------------------------------------

#: the decode-only row: a tiny script reading every frame (the floor under every other row)
DECODE = ("import sys, cv2\n"
          "cap, n, k = cv2.VideoCapture(sys.argv[1]), int(sys.argv[2]) or sys.maxsize, 0\n"
          "while k < n and cap.read()[0]:\n"
          "    k += 1\n"
          "print(f'frames {k}')\n")
MOTION = ("import sys, cv2\n"
          "from motiontrack.config import PipelineConfig\n"
          "from motiontrack.pipeline import Pipeline\n"
          "from motiontrack.types import Frame\n"
          "cap, n, k = cv2.VideoCapture(sys.argv[1]), int(sys.argv[2]) or sys.maxsize, 0\n"
          "size = (int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))\n"
          "pipe = Pipeline(PipelineConfig(), size, None, cap.get(cv2.CAP_PROP_FPS) or 25.0)\n"
          "while k < n:\n"
          "    ok, image = cap.read()\n"
          "    if not ok:\n"
          "        break\n"
          "    pipe.motion(Frame(index=k, image=image, timestamp=k / 25.0))\n"
          "    k += 1\n"
          "print(f'frames {k}')\n")
TUTORIAL = Path(__file__).with_name("tutorial.py")
#: motiontrack's default codec (VP8 WebM) and OpenCV's fast writers
TUTORIAL_FOURCCS = "VP80,mp4v,MJPG,XVID"
#: the per-run measures of a row, in its table's order
MEASURES = (("wall_s", "wall s", "{:.2f}"), ("fps", "fps", "{:.0f}"), ("cpu_s", "CPU s", "{:.2f}"),
            ("peak_rss_mb", "peak RSS MB", "{:.0f}"))
ACCURACY = ("recall", "precision", "MOTA", "IDF1", "HOTA")


@dataclass
class ProcessRow:
    """A whole-process row: its command line given the folder its run writes into, and its runs
    (one a round, in round order)."""

    name: str
    kind: str                          # "decode", "tutorial" or "track"
    command: Callable[[Path], list[str]]
    video: bool = False                # writes an annotated video
    runs: list[ChildRun] = field(default_factory=list)
    frames: list[int] = field(default_factory=list)
    accuracy: dict[str, float] | None = None

    @property
    def folder(self) -> str:
        """The name of the folder each of its runs writes into."""
        return self.name.replace(" --", "_").replace(" ", "_")

    def values(self, key: str) -> list[float]:
        if key == "fps":
            return [f / r.wall_s for f, r in zip(self.frames, self.runs)]
        return [getattr(r, key) for r in self.runs]

    def predictions(self, folder: Path) -> Path | None:
        """The boxes a run in ``folder`` wrote (a MOT file), None for the decode row."""
        return {"tutorial": folder / "boxes.txt", "track": folder / "out" / "tracks.txt"}.get(self.kind)

    def frames_of(self, folder: Path, run: ChildRun) -> int:
        """The frames a run processed: from its summary (track) or its last line (the scripts)."""
        if self.kind == "track":
            return int(json.loads((folder / "out" / "summary.json").read_text())["frames"])
        return int(run.stdout.split()[1])   # "frames N ..."


def process_rows(video: Path, frames: int | None, fourccs: list[str]) -> list[ProcessRow]:
    py, src, n = sys.executable, str(video), str(frames or 0)
    tool = motiontrack_command()
    limit = ["--max-frames", str(frames)] if frames else []

    def tut(d: Path) -> list[str]:
        return [py, str(TUTORIAL), src, "--frames", n, "--out", str(d / "boxes.txt")]

    rows = [ProcessRow("decode only", "decode", lambda d: [py, "-c", DECODE, src, n]),
            ProcessRow("motion stage alone", "decode", lambda d: [py, "-c", MOTION, src, n]),
            ProcessRow("tutorial", "tutorial", tut)]
    for code in fourccs:
        ext = tutorial.FOURCC_EXTENSIONS.get(code, ".avi")
        rows.append(ProcessRow(f"tutorial + video {code}", "tutorial", video=True, command=(
            lambda d, code=code, ext=ext: [*tut(d), "--video", str(d / f"tutorial{ext}"), "--fourcc", code])))
    for name, extra, with_video in (("track", [], True), ("track --no-video", ["--no-video"], False),
                                    ("track --preset people", ["--preset", "people"], True),
                                    ("track --preset people --no-video",
                                     ["--preset", "people", "--no-video"], False)):
        rows.append(ProcessRow(name, "track", video=with_video, command=(
            lambda d, extra=extra: [*tool, "track", src, "-o", str(d / "out"), *limit, *extra])))
    return rows


def opencv_writes(fourcc: str) -> bool:
    """Whether ``cv2.VideoWriter`` of this installation opens ``fourcc`` in its container."""
    if len(fourcc) != 4:
        return False
    # OpenCV's FFmpeg backend warns on stderr (fd 2) that WebM has no tag for VP80, and writes it
    # anyway: the probe keeps it off the report
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null, tempfile.TemporaryDirectory() as d:
            os.dup2(null.fileno(), 2)
            w = cv2.VideoWriter(str(Path(d) / f"probe{tutorial.FOURCC_EXTENSIONS.get(fourcc, '.avi')}"),
                                cv2.VideoWriter_fourcc(*fourcc), 10.0, (64, 48))
            ok = w.isOpened()
            w.release()
    finally:
        os.dup2(saved, 2)
        os.close(saved)
    return ok


def measure(rows: list[ProcessRow], rounds: int, work: Path) -> None:
    """Every row once a round, the order rotated by one each round; the first round's outputs are
    kept for scoring."""
    for r in range(rounds):
        order = rows[r % len(rows):] + rows[:r % len(rows)]
        print(f"round {r + 1}/{rounds}:", end="", file=sys.stderr, flush=True)
        for row in order:
            folder = work / f"round{r}" / row.folder
            folder.mkdir(parents=True)
            run = run_child(row.command(folder))
            row.runs.append(run)
            row.frames.append(row.frames_of(folder, run))
            print(f" {row.name} {run.wall_s:.1f} s;", end="", file=sys.stderr, flush=True)
            if r > 0:
                shutil.rmtree(folder)
        print(file=sys.stderr, flush=True)


def spread(values: list[float]) -> dict[str, float]:
    return {"median": statistics.median(values), "min": min(values), "max": max(values)}


def cell(values: list[float], fmt: str) -> str:
    s = spread(values)
    return f"{fmt.format(s['median'])} ({fmt.format(s['min'])}-{fmt.format(s['max'])})"


def speedups(row: ProcessRow, ref: ProcessRow) -> list[float]:
    """Each round's fps of ``row`` over the same round's fps of ``ref``."""
    return [a / b for a, b in zip(row.values("fps"), ref.values("fps"))]


def video_cost_ms(with_video: ProcessRow, without: ProcessRow, key: str = "wall_s") -> list[float]:
    """Each round's time per frame that the annotated video adds (``key``: wall or CPU)."""
    return [(v - p) / f * 1e3 for v, p, f in zip(with_video.values(key), without.values(key),
                                                  with_video.frames)]


def whole_process(args: argparse.Namespace, video: Path, gt: Annotations) -> None:
    fourccs = [c.strip() for c in args.tutorial_fourccs.split(",") if c.strip()]
    skipped = [c for c in fourccs if not opencv_writes(c)]
    fourccs = [c for c in fourccs if c not in skipped]
    if not fourccs:
        sys.exit(f"OpenCV writes none of --tutorial-fourccs {args.tutorial_fourccs} here")
    rows = process_rows(video, args.frames, fourccs)
    by_name = {r.name: r for r in rows}
    with tempfile.TemporaryDirectory(prefix="throughput-") as work:
        cache_bytecode(Path(work))
        for row in rows:   # a warm-up run of each row fills the bytecode cache
            (Path(work) / "warm-up" / row.folder).mkdir(parents=True)
            run_child(row.command(Path(work) / "warm-up" / row.folder))
        shutil.rmtree(Path(work) / "warm-up")
        measure(rows, args.rounds, Path(work))
        for row in rows:
            path = row.predictions(Path(work) / "round0" / row.folder)
            if path is not None:
                row.accuracy = score(gt, read_mot(path, kind="results"), row.frames[0])
    n = rows[0].frames[0]
    if any(f != n for row in rows for f in row.frames):
        sys.exit("the rows processed different numbers of frames: "
                 + ", ".join(f"{r.name} {r.frames}" for r in rows))
    plain = by_name["tutorial"]
    tut_videos = [r for r in rows if r.kind == "tutorial" and r.video]
    tut_video = min(tut_videos, key=lambda r: statistics.median(r.values("wall_s")))
    code = tut_video.name.rsplit(" ", 1)[1]
    refs = {r.name: (tut_video if r.video else plain) for r in rows}

    print(f"PETS09-S2L1 View 1, {n} frames of 768x576; one fresh process per row and round, "
          f"median (min-max) of {args.rounds} interleaved rounds; OpenCV {cv2.__version__}")
    print(f"tutorial + video: cv2.VideoWriter {code}, the fastest of "
          f"{', '.join(fourccs)} (median wall)" + (f"; OpenCV here writes none of {', '.join(skipped)}"
                                                   if skipped else ""))
    print(f"{'row':<34}" + "".join(f"{h:>20}" for _, h, _ in MEASURES) + f"{'x tutorial':>20}")
    for row in rows:
        ref = refs[row.name]
        x = "" if row is ref else cell(speedups(row, ref), "{:.2f}")
        print(f"{row.name:<34}" + "".join(f"{cell(row.values(k), fmt):>20}" for k, _, fmt in MEASURES)
              + f"{x:>20}")
    print("x tutorial: each round's fps over the same round's tutorial run (video rows: over the "
          f"tutorial + video {code})")
    print(f"\naccuracy (first round's outputs)\n{'row':<34}" + "".join(f"{k:>10}" for k in ACCURACY))
    for row in rows:
        if row.accuracy:
            print(f"{row.name:<34}" + "".join(f"{row.accuracy[k]:>10.3f}" for k in ACCURACY))

    track, track_nv = by_name["track"], by_name["track --no-video"]
    people, people_nv = by_name["track --preset people"], by_name["track --preset people --no-video"]
    cost = {name: {key: spread(video_cost_ms(v, p, key)) for key in ("wall_s", "cpu_s")}
            for name, v, p in (("default", track, track_nv), ("people", people, people_nv))}
    video_rss = track.values("peak_rss_mb") + people.values("peak_rss_mb")
    # (what, its values over the runs, the value judged, op, bound, how it is judged)
    targets = [
        (f"track >= 2x tutorial + video {code}", speedups(track, tut_video), "median", ">=", 2.0,
         "x, median of the rounds' ratios"),
        ("track --no-video >= 2.5x tutorial", speedups(track_nv, plain), "median", ">=", 2.5,
         "x, median of the rounds' ratios"),
        ("track --preset people --no-video >= 100 fps", people_nv.values("fps"), "median", ">=", 100.0,
         "fps, median"),
        ("annotated video <= 3 ms/frame over --no-video", video_cost_ms(track, track_nv), "median",
         "<=", 3.0, "ms/frame, median of the rounds' wall-time differences"),
        ("peak RSS with annotated video < 300 MB", video_rss, "max", "<", 300.0,
         "MB, the largest of the track and track --preset people runs"),
    ]
    print("\ntargets (range over the runs in brackets)")
    results = []
    for label, values, judged, op, bound, how in targets:
        value = spread(values)
        v = value[judged]
        met = {">=": v >= bound, "<=": v <= bound, "<": v < bound}[op]
        results.append({"target": label, "judged": judged, "op": op, "bound": bound, **value,
                        "met": met})
        print(f"  {'met   ' if met else 'MISSED'}  {label}: {v:.2f} {how} "
              f"({value['min']:.2f}-{value['max']:.2f})")
    motion = by_name["motion stage alone"]
    cpu_ratio = [t / m for t, m in zip(plain.values("cpu_s"), motion.values("cpu_s"))]
    print(f"  (info)  motion stage alone (decode, preprocess, KNN, clean-up; one thread): "
          f"{cell(speedups(motion, plain), '{:.2f}')} x the tutorial's fps, "
          f"{cell(cpu_ratio, '{:.2f}')} x less CPU than the tutorial (what the default model "
          "leaves for --no-video's ratio on a machine the runs keep busy)")
    print(f"  (info)  track --preset people with video: {cell(people.values('fps'), '{:.0f}')} fps")
    for name, c in cost.items():
        print(f"  (info)  annotated video cost, {name}: {c['wall_s']['median']:.2f} ms/frame wall "
              f"({c['wall_s']['min']:.2f}-{c['wall_s']['max']:.2f}), {c['cpu_s']['median']:.2f} ms/frame "
              f"CPU ({c['cpu_s']['min']:.2f}-{c['cpu_s']['max']:.2f})")

    if args.json:
        doc = {
            "video": str(video), "frames": n, "rounds": args.rounds, "opencv": cv2.__version__,
            "tutorial_video_fourcc": code, "tutorial_fourccs_skipped": skipped,
            "rows": {row.name: {
                "command": [str(a) for a in row.command(Path("OUT"))], "video": row.video,
                "runs": [{"wall_s": r.wall_s, "cpu_s": r.cpu_s, "peak_rss_mb": r.peak_rss_mb,
                          "frames": f, "fps": f / r.wall_s} for r, f in zip(row.runs, row.frames)],
                **{key: spread(row.values(key)) for key, _, _ in MEASURES},
                "x_tutorial": (None if row is refs[row.name] else
                               {"reference": refs[row.name].name, **spread(speedups(row, refs[row.name]))}),
                "accuracy": row.accuracy,
            } for row in rows},
            "video_cost_ms_per_frame": cost,
            "targets": results,
        }
        Path(args.json).write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_data_argument(ap)
    ap.add_argument("--frames", type=int, help="frames per run (default: every frame of the clip; "
                    "300 with --in-process)")
    ap.add_argument("--rounds", "--repeat", type=int, default=5,
                    help="interleaved rounds, each running every row once (default 5)")
    ap.add_argument("--json", metavar="FILE", help="also write every run and the targets as JSON")
    ap.add_argument("--tutorial-fourccs", default=TUTORIAL_FOURCCS, metavar="LIST",
                    help=f"codecs of the tutorial + video rows (default {TUTORIAL_FOURCCS})")
    ap.add_argument("--in-process", action="store_true",
                    help="the stages side by side in this process instead of whole processes")
    args = ap.parse_args()
    if args.frames is not None and args.frames < 1:
        ap.error(f"--frames must be at least 1, got {args.frames}")
    if args.rounds < 1:
        ap.error(f"--rounds must be at least 1, got {args.rounds}")
    if args.in_process and args.json:
        ap.error("--json is written by the whole-process rows, not with --in-process")
    video = pets_video(args.data)
    gt = read_mot(video.parent / "gt_mot15.txt", kind="gt")
    (in_process if args.in_process else whole_process)(args, video, gt)


if __name__ == "__main__":
    main()
