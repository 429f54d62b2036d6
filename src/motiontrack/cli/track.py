"""``motiontrack track SOURCE``: video in, tracks and annotated video out."""

from __future__ import annotations

import argparse
import logging
import sys

log = logging.getLogger("motiontrack")


def register(sub: argparse._SubParsersAction) -> None:
    from ..config_flags import add_flag
    from ._common import CodecOption, out_help
    from ._sinks import add_sink_options
    from ._common import add_scoring_option

    p = sub.add_parser(
        "track", help="track moving objects in a video, camera, stream, image folder or synth: scene",
        description="Run the pipeline on SOURCE and write annotated video, tracks.txt (MOTChallenge), "
                    "summary.json and the resolved config.toml to the output folder.")
    p.add_argument("source", help="video file, camera index (0), rtsp/http URL, image folder or glob "
                                  "('input/*.jpg'), or synth:NAME (see `motiontrack list`)")
    p.add_argument("-o", "--out", help=out_help("track"))
    p.add_argument("--preset", help="shipped settings to start from: people, fast (see `motiontrack list`)")
    p.add_argument("--config", help="TOML config file (applied after --preset)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="STAGE.PARAM=VALUE",
                   help="override one config field, e.g. --set motion.method=knn (repeatable)")
    add_flag(p, "--start")
    add_flag(p, "--max-frames")
    add_flag(p, "--fps")
    add_flag(p, "--no-video")
    add_flag(p, "--mask-video")
    p.add_argument("--mask-images", metavar="DIR",
                   help="also write the motion mask of every frame as DIR/bin%%06d.png (0/255, "
                        "source size, numbered from --start + 1 as CDnet numbers its input) for "
                        "`motiontrack evaluate-masks --pred DIR`")
    p.add_argument("--save", default="", metavar="STREAMS",
                   help="also write intermediate movies: background,difference,motion,annotated")
    add_flag(p, "--codec", action=CodecOption)
    p.add_argument("--gt", help="ground truth to score the run against (any supported format)")
    add_scoring_option(p)
    p.add_argument("--detections", help="MOTChallenge det.txt: track these detections instead of "
                                        "detecting motion")
    p.add_argument("--min-score", type=float, default=None,
                   help="with --detections: drop detections below this confidence")
    add_flag(p, "--camera")
    add_flag(p, "--detector", metavar="onnx:MODEL")
    add_flag(p, "--detector-names", metavar="FILE")
    p.add_argument("--scene", help="scene file (TOML): line crossings, zone dwell, stationary and "
                                   "speeding events in events.jsonl and counts.csv, lines and zones "
                                   "on the annotated video (docs/analytics.md)")
    p.add_argument("--bin-s", type=float, default=60.0,
                   help="with --scene: seconds per row of counts.csv (default 60)")
    p.add_argument("--by-class", action="store_true",
                   help="with --scene: each class's line crossings in counts.csv and a heat map "
                        "of each class, heatmap_person.png ... (docs/classes.md)")
    p.add_argument("--show", action="store_true",
                   help="live view, a file played at its own frame rate: a window (q quits, "
                        "space pauses) with OpenCV's GUI build; with the headless build the serve "
                        "page of this source on 127.0.0.1 (docs/serve.md; its editor edits "
                        "--scene), kept open after the run until Ctrl-C")
    p.add_argument("--port", type=int, default=0,
                   help="with --show and headless OpenCV: the page's port (default: a free one)")
    p.add_argument("--allowed-host", action="append", default=[], metavar="NAME",
                   help="with --show and headless OpenCV: one more host name the page answers "
                        "to (repeatable; default: localhost, 127.0.0.1 and [::1] only)")
    add_sink_options(p, "the source's name, as the run folder's")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.set_defaults(func=cmd_track)


def _build_config(args):
    from ..config import load_config
    from ..config_activity import warn_inactive_overrides
    from ._common import run_overrides

    overrides = run_overrides(args, ("start", "max_frames", "fps", "codec", "no_video",
                                     "mask_video", "camera", "detector", "detector_names"))
    cfg = load_config(args.config, overrides, preset=args.preset)
    warn_inactive_overrides(cfg, args.overrides)
    return cfg


def _has_gui() -> bool:
    import cv2

    info = cv2.getBuildInformation()
    gui_line = next((ln for ln in info.splitlines() if ln.strip().startswith("GUI:")), "GUI: NONE")
    return "NONE" not in gui_line.upper()


def _live_view(args):
    """--show without a GUI: the serve page of this source, served while the job runs."""
    from ..errors import ConfigError
    from ..run.folders import source_name

    if not 0 <= args.port < 65536:
        raise ConfigError(f"--port must be in 0..65535 (0: a free one), got {args.port}")
    try:
        from ..serve.view import LiveView, view_name
    except ImportError as exc:
        raise ConfigError(f"--show needs a GUI build of OpenCV or the web extras ({exc.name} is "
                          "missing): pip install 'motiontrack[serve]'") from None
    view = LiveView(view_name(source_name(args.source)), port=args.port, scene=args.scene,
                    allowed=args.allowed_host)
    print(f"live view: {view.url}  (Ctrl-C stops)", file=sys.stderr, flush=True)
    view.open_browser()
    return view


def _viewer():
    """A frame callback for --show in a window (OpenCV's GUI build)."""
    import cv2

    state = {"paused": False}

    def show(img) -> bool:
        cv2.imshow("motiontrack", img)
        while True:
            key = cv2.waitKey(0 if state["paused"] else 1) & 0xFF
            if key == ord("q"):
                cv2.destroyAllWindows()
                return False
            if key == ord(" "):
                state["paused"] = not state["paused"]
                continue
            if not state["paused"]:
                return True

    return show


def cmd_track(args) -> int:
    from ..io.mot import read_mot
    from ..run import track_job
    from ._common import frame_loop, output_folder, read_gt
    from ._sinks import sink_settings, sink_targets

    sinks = sink_targets(args)
    settings = sink_settings(args)
    cfg = _build_config(args)
    gt = read_gt(args.gt) if args.gt else None
    det = None
    if args.detections:
        det = read_mot(args.detections, kind="det")
        if args.min_score is not None:
            det = det.select(det.scores >= args.min_score)
    window = args.show and _has_gui()
    view = _live_view(args) if args.show and not window else None
    try:
        job = track_job(args.source, cfg, output_folder(args, "track"), force=args.force, gt=gt,
                        detections=det, show=_viewer() if window else None, save=args.save,
                        mask_images=args.mask_images, scoring=args.scoring, scene=args.scene,
                        bin_s=args.bin_s, by_class=args.by_class, sinks=sinks,
                        camera_name=args.camera_name,
                        sink_settings=settings, pace=args.show,
                        writers=[view.writer()] if view else ())
        log.info("source %s", job.info.describe())
        with frame_loop(job.expected_frames()) as loop:
            summary = job.run(progress=loop.update, should_stop=loop.stop)
        _print_summary(summary)
        if view is not None and not loop.stop():
            _keep_open(view)
    finally:
        if view is not None:
            view.close()
    return 0


def _keep_open(view) -> None:
    """The run is over: the page keeps its last picture, events and counts until Ctrl-C."""
    import time

    from ._common import GracefulStop

    print(f"run finished; the live view stays at {view.url} until Ctrl-C", file=sys.stderr,
          flush=True)
    with GracefulStop() as stop:
        while not stop.stop():
            time.sleep(0.1)


def _print_summary(s) -> None:
    lines = [f"frames    {s.frames} in {s.seconds:.2f} s ({s.fps:.1f} fps)",
             f"tracks    {s.tracks}",
             f"status    {s.status}" + (" (input truncated)" if s.truncated else "")]
    if s.accuracy:
        from ._common import accuracy_line

        lines.append(accuracy_line(s.accuracy))
    masks = s.extra.get("mask_images")
    lines.append(f"outputs   {', '.join(s.outputs.values())}"
                 + (f", {masks['images']} masks in {masks['folder']}" if masks else ""))
    print("\n".join(lines))
