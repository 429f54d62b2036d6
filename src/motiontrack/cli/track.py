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
    p.add_argument("source", nargs="?",
                   help="video file, camera index (0), rtsp/http URL, image folder or glob "
                        "('input/*.jpg'), or synth:NAME (see `motiontrack list`); optional with "
                        "--detections (then only for drawing)")
    p.add_argument("-o", "--out", help=out_help("track"))
    p.add_argument("--preset", help="shipped settings to start from: people, fast, detections "
                                    "(the default with --detections; see `motiontrack list`)")
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
                                        "detecting motion; without SOURCE the frame count, size "
                                        "and rate come from the seqinfo.ini beside it or in the "
                                        "folder above, or from --size and --fps")
    p.add_argument("--detections-folder", metavar="SPLIT",
                   help="track every SPLIT/<seq>/det/det.txt (a MOTChallenge split) into "
                        "OUT/<seq>.txt: with -o TRACKERS/NAME/data, `motiontrack evaluate "
                        "--gt-folder SPLIT --trackers-folder TRACKERS` scores them")
    p.add_argument("--size", metavar="WxH",
                   help="with --detections and no SOURCE: the frame size, e.g. 640x480 (instead "
                        "of seqinfo.ini's)")
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
    preset = args.preset
    if preset is None and (args.detections or args.detections_folder):
        preset = "detections"   # a detector's boxes: the detection-driven tracker
    cfg = load_config(args.config, overrides, preset=preset)
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


def _size(text: str | None) -> tuple[int, int] | None:
    from ..errors import ConfigError

    if text is None:
        return None
    w, sep, h = text.lower().partition("x")
    if not (sep and w.isdigit() and h.isdigit() and int(w) > 0 and int(h) > 0):
        raise ConfigError(f"--size must be WIDTHxHEIGHT in pixels, e.g. 640x480, got {text!r}")
    return int(w), int(h)


def _check_detection_options(args) -> None:
    """The combinations of SOURCE, --detections and --detections-folder that make a run."""
    from ..errors import ConfigError

    if args.detections_folder:
        if args.source or args.detections:
            raise ConfigError("--detections-folder tracks a whole split: give no SOURCE and no "
                              "--detections")
        if args.out is None:
            raise ConfigError("--detections-folder needs -o DIR (e.g. TRACKERS/NAME/data) for "
                              "its <seq>.txt files")
        one_run = [flag for flag, on in (("--gt", args.gt), ("--scene", args.scene),
                                         ("--show", args.show), ("--save", args.save),
                                         ("--mask-images", args.mask_images)) if on]
        if one_run:
            raise ConfigError(f"{one_run[0]} is an option of one run; --detections-folder writes "
                              "each sequence's tracks only (score them with evaluate "
                              "--gt-folder SPLIT --trackers-folder TRACKERS)")
        return
    if args.source is None and not args.detections:
        raise ConfigError("track needs a SOURCE, or --detections det.txt, or "
                          "--detections-folder SPLIT")
    if args.size and args.source is not None:
        raise ConfigError("--size is for --detections without a SOURCE (a video states its size)")
    if args.source is None and (args.show or args.save):
        raise ConfigError(f"{'--show' if args.show else '--save'} draws on the source's "
                          "pictures: give SOURCE with --detections")


def _split(args, cfg) -> int:
    """``--detections-folder SPLIT -o DIR``: every sequence's tracks in DIR/<seq>.txt."""
    from ..run.detections import track_split

    def done(name, tracks) -> None:
        log.info("%s: %d rows, %d tracks", name, len(tracks), len(set(tracks.ids.tolist())))

    files = track_split(args.detections_folder, args.out, cfg, size=_size(args.size),
                        min_score=args.min_score, force=args.force, done=done)
    print(f"sequences {len(files)}\noutputs   {args.out}")
    return 0


def cmd_track(args) -> int:
    from ..run import track_job
    from ._common import frame_loop, output_folder, read_gt
    from ._sinks import sink_settings, sink_targets

    _check_detection_options(args)
    if args.source is None and not args.detections_folder:
        args.overrides = [*args.overrides, "output.video=false"]   # nothing to draw on
    cfg = _build_config(args)
    if args.detections_folder:
        return _split(args, cfg)
    sinks = sink_targets(args)
    settings = sink_settings(args)
    gt = read_gt(args.gt) if args.gt else None
    det = source = None
    if args.detections:
        from ..run.detections import (detections_sequence, pictureless_source,
                                      read_detections)

        det = read_detections(args.detections, args.min_score)
        if args.source is None:
            source = pictureless_source(detections_sequence(args.detections, det,
                                                            _size(args.size)), cfg)
    window = args.show and _has_gui()
    view = _live_view(args) if args.show and not window else None
    try:
        job = track_job(args.source if source is None else source, cfg,
                        output_folder(args, "track") if source is None or args.out
                        else _named_folder(source.info.name),
                        force=args.force, gt=gt,
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


def _named_folder(name: str):
    """A new run folder named after the sequence of detections tracked without a SOURCE."""
    from ..run.folders import new_run_folder

    return new_run_folder("track", name)


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
