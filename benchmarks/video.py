"""The annotated video's cost on the PETS clip (768x576): encoders side by side, and `track` with and
without its video from process start.

--encoders  The first --frames frames, annotated as `track` draws them, are encoded by each
            alternative in turn, --rounds times (one round runs every row once, every other round
            in reverse order). Printed per row: the median over rounds of the process's CPU time
            per frame (user + sys of every thread: encoders that spin-wait between their threads
            pay for it here), the wall time per frame, the file's size per frame and the Y-PSNR
            of the decoded video against the drawn frames (BT.601 limited range, as encoded).
--track     `motiontrack track PETS -o DIR -q --force` with --no-video, then with the video of
            each --codec, --rounds interleaved rounds of separate processes: the median wall time
            from process start, the median CPU time (user + sys), and the peak RSS of each run;
            the video's cost per frame is the difference to the --no-video run of the same round.

--drawing   What the run's own thread spends on a frame's picture: the annotated frame, the copy
            it is drawn on, the conversion to I420, the legend and a scene's zone tint drawn once
            per frame size against drawn on every frame (this thread's CPU per call, the fastest
            of --rounds runs over --frames frames).
--gil       Whether PyAV releases the GIL while it encodes: the main thread counts in a pure-Python
            loop while a second thread encodes VP8 with the default's settings; a call that held
            the GIL would see the count stand still.

Wall times move with the machine's load; on a loaded machine compare the CPU columns.

Run: .venv/bin/python benchmarks/video.py --encoders [--frames 100] [--rounds 3]
     .venv/bin/python benchmarks/video.py --track [--codec vp80 --codec h264] [--rounds 5]
     .venv/bin/python benchmarks/video.py --drawing --gil
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from fractions import Fraction
from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from motiontrack.config import PipelineConfig
from motiontrack.io.sources import open_source
from motiontrack.io.video import VideoSink
from motiontrack.run.processors import TrackProcessor

from _pets import add_data_argument, pets_video  # benchmarks/ is on sys.path when a script here runs

VP8 = {"deadline": "realtime", "crf": "10"}
#: name → (container, encoder, options, bit rate cap, encoder threads)
PYAV_ROWS = {
    "VP8 realtime cpu-used 8 (auto speed), 2 threads, FFmpeg's bgr24 conversion":
        ("webm", "libvpx", {**VP8, "cpu-used": "8"}, 20_000_000, 2, "bgr24"),
    "VP8 realtime cpu-used 8 (auto speed), 1 thread": ("webm", "libvpx", {**VP8, "cpu-used": "8"},
                                                      20_000_000, 1, "i420"),
    "VP8 realtime cpu-used -16 (fixed speed), 2 threads":
        ("webm", "libvpx", {**VP8, "cpu-used": "-16"}, 20_000_000, 2, "i420"),
    "VP8 realtime cpu-used -16, 1 thread, FFmpeg's bgr24 conversion":
        ("webm", "libvpx", {**VP8, "cpu-used": "-16"}, 20_000_000, 1, "bgr24"),
    "VP8 realtime cpu-used -16, 1 thread": ("webm", "libvpx", {**VP8, "cpu-used": "-16"},
                                           20_000_000, 1, "i420"),
    "VP8 realtime cpu-used -16, crf 16, 1 thread":
        ("webm", "libvpx", {**VP8, "cpu-used": "-16", "crf": "16"}, 20_000_000, 1, "i420"),
    "VP8 realtime cpu-used -16, crf 16, static-thresh 500, 1 thread":
        ("webm", "libvpx", {**VP8, "cpu-used": "-16", "crf": "16", "static-thresh": "500"},
         20_000_000, 1, "i420"),
    "VP8 realtime cpu-used -16, crf 16, static-thresh 1000, 1 thread":
        ("webm", "libvpx", {**VP8, "cpu-used": "-16", "crf": "16", "static-thresh": "1000"},
         20_000_000, 1, "i420"),
    "VP8 realtime cpu-used -16, crf 16, static-thresh 2000, 1 thread":
        ("webm", "libvpx", {**VP8, "cpu-used": "-16", "crf": "16", "static-thresh": "2000"},
         20_000_000, 1, "i420"),
    "VP9 realtime cpu-used 8, row-mt, 1 thread":
        ("webm", "libvpx-vp9", {**VP8, "cpu-used": "8", "row-mt": "1"}, 20_000_000, 1, "i420"),
    "H.264 libx264 veryfast crf 23, 1 thread": ("mp4", "libx264", {"preset": "veryfast", "crf": "23"},
                                                0, 1, "i420"),
    "H.264 libx264 superfast crf 23, 1 thread": ("mp4", "libx264", {"preset": "superfast",
                                                                    "crf": "23"}, 0, 1, "i420"),
    "H.264 libx264 ultrafast crf 23, 1 thread": ("mp4", "libx264", {"preset": "ultrafast",
                                                                    "crf": "23"}, 0, 1, "i420"),
    "H.264 libx264 ultrafast crf 23, 2 threads": ("mp4", "libx264", {"preset": "ultrafast",
                                                                     "crf": "23"}, 0, 2, "i420"),
    "H.264 libx264 ultrafast crf 26, 1 thread": ("mp4", "libx264", {"preset": "ultrafast",
                                                                    "crf": "26"}, 0, 1, "i420"),
}
#: name → (OpenCV fourcc, extension)
OPENCV_ROWS = {
    "OpenCV VP80 (cv2.VideoWriter, no speed settings)": ("VP80", ".webm"),
    "OpenCV mp4v (MPEG-4 part 2, browsers do not play it)": ("mp4v", ".mp4"),
    "OpenCV MJPG (AVI)": ("MJPG", ".avi"),
}
#: the product's own sink (its encoder thread and settings), per codec
SINK_ROWS = {"motiontrack VideoSink vp80 (the default: static-thresh 1000)": "vp80",
             "motiontrack VideoSink h264 (ultrafast)": "h264"}


def annotated_frames(video: Path, n: int) -> list[np.ndarray]:
    """The first ``n`` frames of ``video`` as `track` draws them (default config)."""
    src = open_source(str(video))
    proc = TrackProcessor(PipelineConfig(), src.info)
    out = []
    for result in proc.results(src):
        out.append(proc.annotate(result))
        if len(out) == n:
            break
    src.close()
    return out


def encode_pyav(frames: list[np.ndarray], path: Path, fps: float, container: str, encoder: str,
                options: dict, bit_rate: int, threads: int, convert: str) -> None:
    import av

    h, w = frames[0].shape[:2]
    with av.open(str(path), "w", format=container) as out:
        stream = out.add_stream(encoder, rate=Fraction(fps).limit_denominator(1001))
        stream.width, stream.height, stream.pix_fmt = w, h, "yuv420p"
        if bit_rate:
            stream.bit_rate = bit_rate
        stream.options = dict(options)
        stream.thread_count = threads
        for img in frames:
            if convert == "i420":
                frame = av.VideoFrame.from_ndarray(cv2.cvtColor(img, cv2.COLOR_BGR2YUV_I420),
                                                   format="yuv420p")
            else:
                frame = av.VideoFrame.from_ndarray(img, format="bgr24")
            for packet in stream.encode(frame):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)


def encode_opencv(frames: list[np.ndarray], path: Path, fps: float, fourcc: str) -> None:
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, (w, h))
    for img in frames:
        writer.write(img)
    writer.release()


def encode_sink(frames: list[np.ndarray], path: Path, fps: float, codec: str) -> None:
    with VideoSink(path, fps, codec) as sink:
        for img in frames:
            sink.write(img)


def y_psnr(path: Path, frames: list[np.ndarray]) -> float:
    """Mean PSNR (dB) of the decoded luma against the drawn frames' luma."""
    import av

    scores = []
    with av.open(str(path)) as c:
        for img, frame in zip(frames, c.decode(video=0)):
            h = img.shape[0]
            y = frame.to_ndarray(format="yuv420p")[:h].astype(np.float64)
            ref = cv2.cvtColor(img, cv2.COLOR_BGR2YUV_I420)[:h]
            mse = max(np.mean((y - ref) ** 2), 1e-9)
            scores.append(10 * np.log10(255.0 ** 2 / mse))
    return float(np.mean(scores))


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def encoders(args: argparse.Namespace, video: Path) -> None:
    frames = annotated_frames(video, args.frames)
    fps = 10.0
    rows: dict[str, tuple[Callable[[Path], None], str]] = {}
    for name, (container, enc, opts, rate, threads, conv) in PYAV_ROWS.items():
        rows[name] = (lambda p, a=(container, enc, opts, rate, threads, conv):
                      encode_pyav(frames, p, fps, *a), ".webm" if container == "webm" else ".mp4")
    for name, (fourcc, ext) in OPENCV_ROWS.items():
        rows[name] = (lambda p, f=fourcc: encode_opencv(frames, p, fps, f), ext)
    for name, codec in SINK_ROWS.items():
        rows[name] = (lambda p, c=codec: encode_sink(frames, p, fps, c),
                      ".webm" if codec == "vp80" else ".mp4")
    names = [n for n in rows if not args.only or any(s.lower() in n.lower() for s in args.only)]
    cpu: dict[str, list[float]] = {n: [] for n in names}
    wall: dict[str, list[float]] = {n: [] for n in names}
    size: dict[str, float] = {}
    psnr: dict[str, float] = {}
    n = len(frames)
    with tempfile.TemporaryDirectory(prefix="mt-video-bench-") as tmp:
        for rnd in range(args.rounds):
            for name in (names if rnd % 2 == 0 else names[::-1]):
                fn, ext = rows[name]
                path = Path(tmp) / f"out{ext}"
                c0, t0 = _cpu(), time.perf_counter()
                fn(path)
                cpu[name].append((_cpu() - c0) / n * 1e3)
                wall[name].append((time.perf_counter() - t0) / n * 1e3)
                if name not in size:
                    size[name] = path.stat().st_size / n / 1024
                    psnr[name] = y_psnr(path, frames)
                path.unlink()
    print(f"{n} PETS frames annotated as track draws them, {args.rounds} rounds "
          f"(medians); load average {os.getloadavg()[0]:.1f}")
    print(f"{'alternative':70s} {'CPU ms/f':>9s} {'wall ms/f':>10s} {'KiB/f':>7s} {'Y-PSNR':>7s}")
    for name in names:
        print(f"{name:70s} {statistics.median(cpu[name]):9.2f} {statistics.median(wall[name]):10.2f} "
              f"{size[name]:7.1f} {psnr[name]:7.2f}")


def _ms_per_call(fn: Callable[[], object], n: int, rounds: int) -> float:
    """The fastest of ``rounds`` runs of ``n`` calls, in ms of this thread's CPU per call."""
    best = float("inf")
    for _ in range(rounds):
        t0 = time.thread_time()
        for _ in range(n):
            fn()
        best = min(best, (time.thread_time() - t0) / n * 1e3)
    return best


def drawing(args: argparse.Namespace, video: Path) -> None:
    """What `track` spends on a frame's picture besides the encoder, in the run's thread."""
    from types import SimpleNamespace

    from motiontrack.render import annotate as draw
    from motiontrack.render import scene

    src = open_source(str(video))
    proc = TrackProcessor(PipelineConfig(), src.info)
    results = []
    for result in proc.results(src):
        results.append(result)
        if len(results) == args.frames:
            break
    src.close()
    frame = results[0].frame
    it = iter(range(10 ** 9))
    rows = {"annotate a frame (the processor's picture, legend included)":
            lambda: proc.annotate(results[next(it) % len(results)])}
    rows["copy of the frame (the picture is drawn on a copy)"] = frame.copy
    rows["BGR to I420 with OpenCV (into the encoder's buffer)"] = \
        lambda: cv2.cvtColor(frame, cv2.COLOR_BGR2YUV_I420)
    import av

    rows["bgr24 to yuv420p with FFmpeg (PyAV's reformat)"] = \
        lambda: av.VideoFrame.from_ndarray(frame, format="bgr24").reformat(format="yuv420p")
    img = frame.copy()
    entries = (("track", "track (id, trail)"), ("predicted", "track, not seen (predicted)"),
               ("region", "motion region"), ("head", "head"), ("hypothesis", "shape hypothesis"))
    rows["legend of 5 kinds, drawn once per frame size and laid over the frame"] = \
        lambda: draw.draw_legend(img, entries, (4, 560))

    def legend_each_frame() -> None:
        """The legend drawn on the frame itself: the scene under the panel darkened, then the
        symbols and labels (the panel's place from the cached layer)."""
        (y0, y1, x0, x1), ph, _, _ = draw._legend_layer(img.shape, entries, (4, 560), False)
        scale, thick = draw.text_scale(img.shape)
        scale *= 0.8
        font = cv2.FONT_HERSHEY_SIMPLEX
        (_, th), base = cv2.getTextSize("Ag", font, scale, thick)
        row, size, pad = th + base + max(2, th // 3), th + base // 2, max(3, th // 3)
        img[y0:y1, x0:x1] = (img[y0:y1, x0:x1].astype(np.uint16) * 2 // 5).astype(np.uint8)
        for i, (style, label) in enumerate(entries):
            y = y0 + pad + i * row
            draw._swatch(img, style, x0 + pad, y, size, img.shape)
            cv2.putText(img, label, (x0 + 2 * pad + size, y + size - base // 2), font, scale,
                        (255, 255, 255), thick, cv2.LINE_AA)

    rows["legend of 5 kinds, drawn on every frame"] = legend_each_frame
    zones = [SimpleNamespace(name="a", polygon=[[100, 300], [400, 300], [400, 500], [100, 500]]),
             SimpleNamespace(name="b", polygon=[[500, 100], [700, 120], [650, 300]])]
    polygons = tuple(tuple(map(tuple, z.polygon)) for z in zones)
    rows["two zones tinted inside their rectangle (the layer made once)"] = \
        lambda: scene._tint_zones(img, polygons)

    def tint_whole_frame() -> None:
        tinted = img.copy()
        cv2.fillPoly(tinted, [np.array(p, np.int32) for p in polygons], scene.ZONE_COLOR)
        cv2.addWeighted(tinted, 0.15, img, 0.85, 0.0, dst=img)

    rows["two zones tinted by blending a tinted copy of the whole frame"] = tint_whole_frame
    print(f"{len(results)} PETS frames, this thread's CPU per call, the fastest of {args.rounds} "
          f"runs; load average {os.getloadavg()[0]:.1f}")
    for name, fn in rows.items():
        print(f"{name:72s} {_ms_per_call(fn, len(results), args.rounds):7.3f} ms")


def gil(args: argparse.Namespace, video: Path) -> None:
    """Whether PyAV releases the GIL while it encodes: the main thread counts in a pure-Python
    loop while a second thread encodes VP8 as the default does; an encoder call that held the GIL
    would see the count stand still from its start to its end."""
    import threading

    import av

    from motiontrack.io.video import PYAV_MAX_BITRATE, PYAV_OPTIONS

    frames = [cv2.cvtColor(f, cv2.COLOR_BGR2YUV_I420) for f in annotated_frames(video, 30)]
    count = [0]
    steps: list[int] = []
    done = threading.Event()

    def encode() -> None:
        with tempfile.TemporaryDirectory() as tmp, \
                av.open(str(Path(tmp) / "g.webm"), "w", format="webm") as out:
            s = out.add_stream("libvpx", rate=10)
            s.width, s.height, s.pix_fmt = 768, 576, "yuv420p"
            s.options, s.bit_rate, s.thread_count = dict(PYAV_OPTIONS), PYAV_MAX_BITRATE, 1
            for k in range(30 * args.rounds):
                frame = av.VideoFrame.from_ndarray(frames[k % 30], format="yuv420p")
                before = count[0]
                packets = s.encode(frame)
                steps.append(count[0] - before)
                for p in packets:
                    out.mux(p)
        done.set()

    th = threading.Thread(target=encode)
    th.start()
    while not done.is_set():
        count[0] += 1
    th.join()
    moved = sum(1 for d in steps if d > 0)
    print(f"{len(steps)} encoder calls: the main thread's Python loop went on during {moved} of "
          f"them (median {statistics.median(steps)} steps a call); load average "
          f"{os.getloadavg()[0]:.1f}")


def _run(argv: list[str]) -> tuple[float, float, float]:
    """Wall seconds, CPU seconds (user + sys) and peak RSS (MB) of one process."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        sys.exit(f"failed ({proc.returncode}): {' '.join(argv)}")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0


def track(args: argparse.Namespace, video: Path) -> None:
    exe = str(Path(sys.executable).with_name("motiontrack"))
    variants = {"--no-video": ["--no-video"]}
    for codec in args.codec or ["vp80"]:
        variants[f"video {codec}"] = ["--codec", codec]
    frames = 300
    res: dict[str, list[tuple[float, float, float]]] = {k: [] for k in variants}
    with tempfile.TemporaryDirectory(prefix="mt-video-track-") as tmp:
        for rnd in range(args.rounds):
            order = list(variants) if rnd % 2 == 0 else list(variants)[::-1]
            for name in order:
                argv = [exe, "track", str(video), "-o", str(Path(tmp) / "o"), "-q", "--force",
                        *variants[name]]
                res[name].append(_run(argv))
    print(f"motiontrack track PETS ({frames} frames), {args.rounds} interleaved rounds (medians); "
          f"load average {os.getloadavg()[0]:.1f}")
    base = res["--no-video"]
    print(f"{'run':16s} {'wall s':>7s} {'CPU s':>7s} {'peak RSS MB':>12s} {'+wall ms/f':>11s} "
          f"{'+CPU ms/f':>10s}")
    for name, runs in res.items():
        dw = statistics.median((r[0] - b[0]) / frames * 1e3 for r, b in zip(runs, base))
        dc = statistics.median((r[1] - b[1]) / frames * 1e3 for r, b in zip(runs, base))
        print(f"{name:16s} {statistics.median(r[0] for r in runs):7.2f} "
              f"{statistics.median(r[1] for r in runs):7.2f} {max(r[2] for r in runs):12.1f} "
              f"{dw:11.2f} {dc:10.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    add_data_argument(ap)
    ap.add_argument("--encoders", action="store_true", help="encoders side by side")
    ap.add_argument("--track", action="store_true", help="track with and without the video")
    ap.add_argument("--drawing", action="store_true",
                    help="drawing and conversion costs in the run's thread")
    ap.add_argument("--gil", action="store_true",
                    help="does the main thread run Python while PyAV encodes")
    ap.add_argument("--frames", type=int, default=100, help="frames encoded (--encoders)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--only", action="append", help="rows whose name contains this (--encoders)")
    ap.add_argument("--codec", action="append", help="codec of a video run (--track; default vp80)")
    args = ap.parse_args()
    video = pets_video(args.data)
    if not (args.encoders or args.track or args.drawing or args.gil):
        ap.error("give --encoders, --track, --drawing and/or --gil")
    if args.drawing:
        drawing(args, video)
    if args.gil:
        gil(args, video)
    if args.encoders:
        encoders(args, video)
    if args.track:
        track(args, video)


if __name__ == "__main__":
    main()
