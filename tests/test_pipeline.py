"""The pipeline end to end: every detector finds the walker, identities survive occlusion and
crossing on the synthetic scenes, and PETS09 is tracked well above the tutorial baseline."""

from __future__ import annotations

import numpy as np
import pytest

import motiontrack

from motiontrack.config import PipelineConfig, load_config
from motiontrack.evaluate.mot import evaluate_tracking
from motiontrack.io.mot import read_mot
from motiontrack.motion import DETECTORS
from motiontrack.synth import parse_synth_spec
from motiontrack.tracking.association import iou_matrix
from motiontrack.types import FrameResult

from helpers import tracks_of


def run_scene(spec, overrides=()):
    """Tracks of a run as Annotations, plus the per-frame results."""
    results = list(motiontrack.track(spec, load_config(None, list(overrides))))
    return tracks_of(results), results


def test_python_api_yields_frame_results():
    results = list(motiontrack.track("synth:walker?n_frames=40"))
    assert len(results) == 40
    assert all(isinstance(r, FrameResult) for r in results)
    assert [r.index for r in results] == list(range(40))
    assert results[-1].mask.dtype == np.uint8 and set(np.unique(results[-1].mask)) <= {0, 255}


WARMUP = 40  # frames: the walker is in view and every model has settled


def test_a_frame_results_rows_are_an_attribute_not_a_method():
    with motiontrack.track("synth:walker?n_frames=40") as frames:
        results = list(frames)
    with_tracks = [r for r in results if r.tracks]
    assert with_tracks
    for r in results:
        assert r.reported == (*((r.index, t) for t in r.tracks), *r.earlier)


def test_the_public_result_objects_hold_values_not_methods():
    """A value of a result is read as ``result.value``; the only methods are conversions."""
    import inspect

    from motiontrack.types import Box, Frame, FrameResult, PeopleFrame, Region, Track

    conversions = {"as_array"}
    for cls in (Box, Region, Track, Frame, FrameResult, PeopleFrame):
        methods = {n for n, v in vars(cls).items() if not n.startswith("_")
                   and inspect.isfunction(v)}
        assert methods <= conversions, (cls.__name__, methods - conversions)


@pytest.mark.parametrize("method", DETECTORS.names())
@pytest.mark.slow
def test_each_detector_finds_the_walker(method):
    # 170 frames: 130 after the warm-up with the walker fully in view
    spec = "synth:walker?n_frames=170"
    gt = parse_synth_spec(spec).ground_truth()
    by_frame = gt.by_frame()
    _, results = run_scene(spec, [f"motion.method={method}"])
    found = []
    for res in results[WARMUP:]:
        rows = by_frame.get(res.index + 1)
        if rows is None or gt.visibility[rows].min() < 0.9:
            continue
        boxes = np.array([r.box.as_array() for r in res.regions]).reshape(-1, 4)
        iou = iou_matrix(gt.boxes[rows], boxes)
        found.append(bool(iou.size and iou.max() >= 0.5))
    assert len(found) > 100
    assert np.mean(found) >= 0.9, f"{method}: walker found on {np.mean(found):.0%} of frames"


@pytest.mark.parametrize("scene", ["walker", "runner", "column", "crossing"])
@pytest.mark.slow
def test_synthetic_types_keep_identities(scene):
    # column: the walker is fully hidden for 20+ frames and must come back with the same id;
    # crossing: the two people's blobs merge for 10+ frames and must come apart with their ids
    spec = f"synth:{scene}"
    pred, _ = run_scene(spec)
    res = evaluate_tracking(parse_synth_spec(spec).ground_truth(), pred, ignore_zero_marked=True)
    assert res["IDSW"] == 0
    assert res["MOTA"] >= 0.9
    assert res["IDF1"] >= 0.95


@pytest.mark.slow
def test_processing_scale_reports_original_pixels():
    spec = "synth:walker?n_frames=120"
    gt = parse_synth_spec(spec).ground_truth()
    for scale in (1.0, 0.5):
        pred, _ = run_scene(spec, [f"preprocess.scale={scale}"])
        res = evaluate_tracking(gt, pred, ignore_zero_marked=True)
        assert res["MOTP"] >= 0.75, scale      # boxes overlap the truth in full-frame pixels


@pytest.mark.slow
def test_roi_mask_blanks_motion_outside(tmp_path):
    import cv2

    roi = np.zeros((480, 640), np.uint8)
    roi[:, 400:] = 255          # the walker starts on the left: nothing before x = 400
    cv2.imwrite(str(tmp_path / "roi.png"), roi)
    pred, _ = run_scene("synth:walker", [f'preprocess.roi="{tmp_path / "roi.png"}"'])
    assert len(pred) > 0
    assert (pred.boxes[:, 0] + pred.boxes[:, 2]).min() > 380


@pytest.mark.data
@pytest.mark.slow
def test_pets09_well_above_the_tutorial_baseline(data):
    # the tutorial baseline (benchmarks/throughput.py) reaches recall 0.53 and precision 0.68 on
    # these 300 frames with no identities at all
    video = data("pets09-s2l1", "video.avi")
    gt = read_mot(data("pets09-s2l1", "gt_mot15.txt"), kind="gt")
    scores = []
    for seed in range(3):
        cfg = load_config(None, [f"motion.knn.seed={seed}"])
        pred = tracks_of(motiontrack.track(str(video), cfg))
        r = evaluate_tracking(gt, pred, ignore_zero_marked=True)
        scores.append({"recall": r["TP"] / (r["TP"] + r["FN"]),
                       "precision": r["TP"] / (r["TP"] + r["FP"]),
                       "MOTA": r["MOTA"], "IDF1": r["IDF1"], "HOTA": r["HOTA"]})
    mean = {k: float(np.mean([s[k] for s in scores])) for k in scores[0]}
    # The identity scores of one run hang on a swap or two inside the group at the sign post, so
    # the floors hold the mean of three seeds of the KNN model (benchmarks/cold_start.py).
    # Measured (seeds 0, 1, 2): recall 0.840, precision 0.900, MOTA 0.739, IDF1 0.814, HOTA 0.581
    # (seed 0 alone: 0.843, 0.906, 0.748, 0.823, 0.584). The floors sit 0.01-0.02 under these
    # means.
    assert mean["recall"] >= 0.82 and mean["precision"] >= 0.88
    assert mean["MOTA"] >= 0.72 and mean["IDF1"] >= 0.79 and mean["HOTA"] >= 0.565


@pytest.mark.data
@pytest.mark.slow
def test_pets09_cold_starts_lose_the_ghosts_of_people_standing_in_the_first_frame(data):
    # A run started mid-clip learns the people standing in its first frame as background; when
    # they walk off, each leaves a ghost joined to them. The pixel-level ghost test
    # (GhostFilter._absorb) cuts those ghosts away. Runs started at frames 61, 161 and 211 (seed
    # 0), scored on the frames they processed: mean MOTA 0.648 without it, 0.653 with it (0.667
    # with it and without giving back the shadow pixels enclosed by a region's foreground,
    # motion.knn.shadow_inside: the people's dark coats their ghosts keep make the ghosts more
    # whole). Over starts every 10 frames from 1 to 221, three seeds each:
    # benchmarks/cold_start.py --starts 0,10,...,220 --seeds 3 [--set motion.ghost_pixels=false].
    video = data("pets09-s2l1", "video.avi")
    gt = read_mot(data("pets09-s2l1", "gt_mot15.txt"), kind="gt")

    def mean_mota(pixels: bool) -> float:
        scores = []
        for start in (60, 160, 210):
            pred = tracks_of(motiontrack.track(str(video), load_config(
                None, [f"source.start={start}", f"motion.ghost_pixels={str(pixels).lower()}"])))
            r = evaluate_tracking(gt.select(gt.frames > start), pred, ignore_zero_marked=True)
            scores.append(r["MOTA"])
        return float(np.mean(scores))

    with_pixels, without = mean_mota(True), mean_mota(False)
    assert with_pixels >= 0.64
    assert with_pixels >= without


@pytest.mark.data
@pytest.mark.slow
def test_pets09_people_preset_splits_groups_by_heads(data):
    # head-based splitting separates people walking together: measured MOTA 0.758, IDF1 0.838,
    # HOTA 0.591 on these 300 frames. The identity scores hang on one or two swaps, so the floors
    # leave room under them.
    video = data("pets09-s2l1", "video.avi")
    gt = read_mot(data("pets09-s2l1", "gt_mot15.txt"), kind="gt")
    pred = tracks_of(motiontrack.track(str(video), load_config(None, preset="people")))
    r = evaluate_tracking(gt, pred, ignore_zero_marked=True)
    assert r["MOTA"] >= 0.72 and r["IDF1"] >= 0.75 and r["HOTA"] >= 0.55


def test_single_object_tracker_bridges_detection_misses():
    # Detections are the walker's exact boxes, except frames 101-110 where the "detector" misses
    # it. Without a bridge the track is not reported in the gap; with KCF it is, on the walker.
    from motiontrack.io.sources import open_source
    from motiontrack.pipeline import Pipeline

    spec = "synth:walker?n_frames=130"
    gt = parse_synth_spec(spec).ground_truth()
    det = gt.select((gt.frames < 101) | (gt.frames > 110))
    reported = {}
    for bridge in ("none", "kcf"):
        cfg = load_config(None, [f"tracker.bridge={bridge}"])
        pipe = Pipeline(cfg, (640, 480), detections=det)
        hits = 0
        for frame in open_source(spec):
            res = pipe.process(frame)
            if 101 <= frame.index + 1 <= 110:
                g = gt.at(frame.index + 1).boxes
                p = np.array([t.box.as_array() for t in res.tracks]).reshape(-1, 4)
                hits += int(iou_matrix(g, p).size and iou_matrix(g, p).max() >= 0.5)
        reported[bridge] = hits
    assert reported["none"] == 0
    assert reported["kcf"] >= 7     # KCF keeps a fixed box while the stride changes the width


def _walk_then_stop(n_walk=40, n_stop=160):
    """A textured 40x90 'person' crosses a noisy background, then stands still."""
    rng = np.random.default_rng(0)
    bg = rng.integers(60, 120, (240, 320, 3), dtype=np.uint8)
    person = rng.integers(150, 255, (90, 40, 3), dtype=np.uint8)
    frames = []
    for t in range(20 + n_walk + n_stop):
        img = bg.copy()
        if t >= 20:
            x = 10 + 4 * min(t - 20, n_walk)
            img[100:190, x:x + 40] = person
        noise = rng.normal(0, 3, img.shape)
        frames.append(np.clip(img + noise, 0, 255).astype(np.uint8))
    return frames


@pytest.mark.parametrize("protect, still_tracked", [(True, True), (False, False)])
@pytest.mark.slow
def test_selective_update_keeps_a_person_who_stops(protect, still_tracked):
    # the temporal-median background absorbs a standing person after about half its history
    # (25 samples x 5 frames); with selective update the tracked person is never learnt
    from motiontrack.io.sources import ArraySource

    cfg = load_config(None, ["motion.method=median", f"motion.median.protect={str(protect).lower()}",
                             "preprocess.scale=1.0", "regions.max_size=0.5"])
    results = list(motiontrack.track(ArraySource(_walk_then_stop()), cfg))
    last = results[-1]
    assert bool(last.tracks) is still_tracked
    if still_tracked:
        assert last.tracks[0].box.x == pytest.approx(10 + 4 * 40, abs=6)


@pytest.mark.slow
def test_people_preset_runs_heads_and_shapes_and_draws_them(tmp_path):
    from motiontrack.cli import main

    out = tmp_path / "o"
    assert main(["track", "synth:crossing?n_frames=60", "--preset", "people", "-o", str(out),
                 "--codec", "mjpg"]) == 0
    cfg = load_config(out / "config.toml")
    assert cfg.people.enabled and cfg.people.heads and cfg.people.shapes
    cfg = load_config(None, preset="people")
    results = list(motiontrack.track("synth:crossing?n_frames=60", cfg))
    assert any(r.people.heads for r in results)
    assert any(r.people.shapes for r in results)


def test_unknown_preset(capsys):
    from motiontrack.cli import main

    assert main(["track", "synth:walker?n_frames=5", "--preset", "nope"]) == 2
    assert "unknown preset 'nope'; valid presets: detections, fast, people" in capsys.readouterr().err


@pytest.mark.slow
def test_ablate_prints_one_row_per_configuration(capsys, tmp_path):
    from motiontrack.cli import main

    code = main(["ablate", "synth:crossing?n_frames=60", "--rows", "1,3", "--json",
                 str(tmp_path / "a.json")])
    assert code == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].split()[:2] == ["configuration", "LOP"]
    assert out[1].startswith("motion + regions only") and out[2].startswith("+ head-based splitting")
    import json

    rows = json.loads((tmp_path / "a.json").read_text())
    assert [r["configuration"] for r in rows] == ["motion + regions only", "+ head-based splitting"]
    assert all(0.0 <= r["localized_object_recall"] <= 1.0 for r in rows)


def test_an_interrupted_ablation_prints_and_writes_the_rows_that_finished(capsys, tmp_path,
                                                                          monkeypatch):
    import json

    import motiontrack.studies.ablate as ablate
    from motiontrack.cli import main

    def execute(specs, jobs=1, on_result=None):   # the second row is stopped by Ctrl-C
        on_result(0, {"row": {"TP": 9, "FP": 1, "FN": 1, "MOTA": 0.8, "IDF1": 0.9, "HOTA": 0.7,
                              "trk_localized_object_precision": 0.9,
                              "trk_localized_object_recall": 0.9}})
        raise KeyboardInterrupt

    monkeypatch.setattr(ablate, "execute", execute)
    code = main(["ablate", "synth:crossing", "--rows", "1,3", "--json", str(tmp_path / "a.json")])
    assert code == 130
    out = capsys.readouterr()
    assert "interrupted after 1 of 2 rows" in out.err
    assert out.out.splitlines()[1].startswith("motion + regions only")
    rows = json.loads((tmp_path / "a.json").read_text())
    assert [(r["configuration"], r["precision"]) for r in rows] == [("motion + regions only", 0.9)]


@pytest.mark.parametrize("stamps, gaps", [
    ([0.0, 0.1, 0.2, 0.5], [1, 1, 1, 3]),      # a 10 fps file: 0.3 s is three periods
    ([5.0, 5.04, 5.08, 5.2], [1, 1, 1, 3]),    # live wall-clock stamps at 25 fps, then a drop
    ([0.0, 0.2, 0.3, 0.5], [1, 1, 1, 2]),      # a gap first is taken as one period until a shorter one shows
])
def test_frame_gaps_from_timestamps(stamps, gaps):
    from motiontrack.pipeline import Pipeline
    from motiontrack.types import Frame

    pipe = Pipeline(PipelineConfig(), (64, 48))
    img = np.zeros((48, 64, 3), np.uint8)
    assert [pipe._frame_gap(Frame(i, img, t)) for i, t in enumerate(stamps)] == gaps


@pytest.mark.slow
def test_head_splitting_without_shapes_keeps_detection_in_its_worker_thread():
    # Heads need only the mask, so with shapes and HOG off the people stage does not force the
    # pipeline to run detection and tracking in one thread; the output is the same either way.
    cfg = load_config(None, ["people.enabled=true", "people.shapes=false"])
    outputs = [[(r.index, [(t.id, t.box) for t in r.tracks], len(r.people.heads) if r.people else 0)
                for r in results] for _pipe, results in _threaded_then_sequential(
                    cfg, "synth:crowd?n_frames=80")]
    assert outputs[0] == outputs[1]
    assert sum(n for _i, _t, n in outputs[0]) > 0


def _threaded_then_sequential(cfg, spec):
    """``(pipeline, its results on spec)`` with the pipeline's own threads, then with detection
    and tracking forced into one thread; each pipeline is yielded before its results are read."""
    from motiontrack.io.sources import open_source
    from motiontrack.pipeline import Pipeline

    for sequential in (False, True):
        src = open_source(spec)
        pipe = Pipeline(cfg, (src.info.width, src.info.height), None, src.info.fps)
        assert pipe.sequential is False
        pipe.sequential = sequential
        yield pipe, pipe.results(src)


@pytest.mark.slow
def test_shapes_fit_the_background_of_their_own_frame_while_the_next_frame_is_detected():
    # The shape tracker reads the detector's background image after each frame. The detector's
    # thread takes it right after its update and hands it on with the frame, so detection of the
    # next frame runs meanwhile and the shapes still see their own frame's background: the
    # tracks and outlines equal those of a run with detection and tracking in one thread. The
    # shapes make the tracking thread the longest, so the detector's thread finds the regions.
    # (KNN without its hold: a detector fed by the tracks runs a frame ahead of them and finds
    # no regions, its masks those of the tracks two frames back: test_samples_pipeline.py)
    import threading

    cfg = load_config(None, ["people.enabled=true", "motion.knn.hold=false"])
    outputs = []
    for pipe, results in _threaded_then_sequential(cfg, "synth:crossing?n_frames=60"):
        sequential = pipe.sequential
        threads = set()
        regions_of = pipe.regions_of

        def recorded(index, motion, regions_of=regions_of, threads=threads):
            threads.add(threading.current_thread())
            return regions_of(index, motion)

        pipe.regions_of = recorded
        outputs.append([(r.index, [(t.id, t.box) for t in r.tracks],
                         [(s.track_id, s.outline.tobytes()) for s in r.people.shapes])
                        for r in results])
        assert (threading.main_thread() in threads) is sequential
    assert outputs[0] == outputs[1]
    assert sum(len(shapes) for _i, _t, shapes in outputs[0]) > 0


def test_motion_carries_the_detector_background_only_for_the_shapes():
    # the background image costs about half a KNN update: taken only when the shapes read it
    from motiontrack.pipeline import Pipeline
    from motiontrack.types import Frame

    img = np.random.default_rng(0).integers(0, 255, (48, 64, 3), np.uint8)
    frame = Frame(0, img, 0.0)
    for overrides, wanted in ((["people.enabled=true"], True),
                              (["people.enabled=true", "people.shapes=false"], False), ([], False)):
        pipe = Pipeline(load_config(None, overrides), (64, 48))
        motion = pipe.motion(frame)
        assert (motion.background is not None) is wanted
        if wanted:
            np.testing.assert_array_equal(motion.background, pipe.detector.background())


@pytest.mark.slow
def test_track_job_with_shapes_writes_what_run_yields(tmp_path):
    # The CLI's job runs `--preset people` with detection in its worker thread (the background
    # image travels with each frame) and writes what `run` yields.
    from motiontrack.pipeline import run
    from motiontrack.run import track_job

    cfg = load_config(None, ["people.enabled=true", "output.video=false"])
    spec = "synth:crossing?n_frames=60"
    job = track_job(spec, cfg, tmp_path / "out")
    assert job.processor.pipe.sequential is False
    job.run()
    written = np.loadtxt(tmp_path / "out" / "tracks.txt", delimiter=",", ndmin=2)[:, :6]
    tracks = tracks_of(run(spec, cfg))
    expected = np.column_stack([tracks.frames, tracks.ids, tracks.boxes])
    np.testing.assert_allclose(written, expected, atol=0.006)   # tracks.txt keeps 2 decimals
    no_shapes = load_config(None, ["people.enabled=true", "people.shapes=false",
                                   "output.video=false"])
    assert track_job(spec, no_shapes, tmp_path / "out2").processor.pipe.sequential is False
    saving = track_job(spec, no_shapes, tmp_path / "out3", save=["background"])
    assert saving.processor.pipe.sequential is True


@pytest.mark.parametrize("border_rule", [True, False])
def test_bridge_lets_go_of_an_object_at_the_image_border(border_rule, monkeypatch):
    # The walker leaves at the left edge; the "detector" stops seeing it once its box is within
    # 10 px of the edge. The KCF bridge carries it on towards the edge and lets go when its box
    # reaches the border (on PETS, bridges held there stick to the background and cost precision:
    # MOTA with the KCF bridge 0.51 without the rule, 0.58 with it). Patched out, the bridge
    # goes on.
    from motiontrack.io.sources import open_source
    from motiontrack.pipeline import Pipeline
    from motiontrack.tracking import bridge as bridge_mod

    if not border_rule:
        monkeypatch.setattr(bridge_mod, "_at_border", lambda *a, **k: False)
    spec = "synth:walker"
    gt = parse_synth_spec(spec).ground_truth()
    det = gt.select(gt.boxes[:, 0] > 10)
    last = int(det.frames.max())
    pipe = Pipeline(load_config(None, ["tracker.bridge=kcf"]), (640, 480), detections=det)
    results = [pipe.process(frame) for frame in open_source(spec)]
    xs = [t.box.x for r in results if r.index + 1 > last for t in r.tracks]
    assert len(xs) >= 3 and min(xs) < 10          # bridged beyond the last detection
    if border_rule:
        assert min(xs) > 2.0                      # ... but never onto the border
    else:
        assert min(xs) <= 2.0


@pytest.mark.slow
def test_knn_masks_do_not_depend_on_the_threads_random_state():
    # OpenCV's KNN draws from the calling thread's random generator; unseeded, a second run in
    # the same thread (or one after anything else used the generator) would give other masks.
    # The detector seeds it per frame, so every run is the same, in any thread.
    import threading

    import cv2

    from motiontrack.io.sources import open_source

    frames = [f.image for f in open_source("synth:crossing?n_frames=40")]

    def masks() -> list[bytes]:
        det = DETECTORS.create("knn")
        return [det.apply(img).tobytes() for img in frames]

    first = masks()
    cv2.randu(np.zeros((50, 50)), 0, 1)     # move this thread's generator on
    again = masks()
    other: list = []
    t = threading.Thread(target=lambda: other.append(masks()))
    t.start()
    t.join()
    assert first == again == other[0]
    assert any(np.frombuffer(m, np.uint8).any() for m in first)  # the walkers are detected


@pytest.mark.slow
def test_knn_seed_gives_another_draw_that_repeats():
    from motiontrack.io.sources import open_source

    frames = [f.image for f in open_source("synth:crossing?n_frames=40")]

    def masks(seed: int) -> list[bytes]:
        det = DETECTORS.create("knn", seed=seed)
        return [det.apply(img).tobytes() for img in frames]

    zero, seven = masks(0), masks(7)
    assert masks(7) == seven
    assert zero != seven
    # a draw, not another detector: the masks differ in a few pixels only
    diff = np.mean([np.mean(np.frombuffer(a, np.uint8) != np.frombuffer(b, np.uint8))
                    for a, b in zip(zero, seven)])
    assert 0 < diff < 0.01


@pytest.mark.slow
def test_knn_model_size_reaches_opencv_and_the_fast_preset_keeps_identities():
    from motiontrack.errors import ConfigError

    det = DETECTORS.create("knn", n_samples=3, knn_samples=1)
    assert (det.sub.getNSamples(), det.sub.getkNNSamples()) == (3, 1)
    default = DETECTORS.create("knn")
    assert (default.sub.getNSamples(), default.sub.getkNNSamples()) == (7, 2)  # OpenCV's own
    fast = load_config(None, preset="fast").motion.knn
    assert (fast.n_samples, fast.knn_samples) == (3, 1)
    # the smaller model still follows both people through the crossing
    spec = "synth:crossing"
    pred, _ = run_scene(spec, ["motion.knn.n_samples=3", "motion.knn.knn_samples=1"])
    res = evaluate_tracking(parse_synth_spec(spec).ground_truth(), pred, ignore_zero_marked=True)
    assert res["IDSW"] == 0 and res["MOTA"] >= 0.9
    with pytest.raises(ConfigError, match="motion.knn.knn_samples must be at most motion.knn.n_samples"):
        load_config(None, ["motion.knn.n_samples=3", "motion.knn.knn_samples=4"])
    with pytest.raises(ConfigError, match="knn_samples"):
        DETECTORS.create("knn", n_samples=3, knn_samples=5)


def test_a_stage_that_raises_stops_the_reading_threads(tmp_path, monkeypatch):
    # an exception inside the pipeline reaches the caller, and the source's decoding thread and
    # the detection worker are stopped before it does (a reading thread left running at
    # interpreter exit aborts the process)
    import threading

    import cv2

    from motiontrack.pipeline import Pipeline, run

    p = tmp_path / "v.avi"
    w = cv2.VideoWriter(str(p), cv2.VideoWriter_fourcc(*"MJPG"), 10, (64, 48))
    for i in range(40):
        w.write(np.full((48, 64, 3), (i * 7) % 255, np.uint8))
    w.release()

    def boom(self, *args, **kwargs):
        raise RuntimeError("stage failed")

    for stage in ("motion", "track"):
        with monkeypatch.context() as m:
            m.setattr(Pipeline, stage, boom)
            with pytest.raises(RuntimeError, match="stage failed"):
                for _ in run(str(p), PipelineConfig()):
                    pass
        assert not [t for t in threading.enumerate() if t.name == "motiontrack-decode"], stage


def _square_frames(n, bright, x0=10):
    """``n`` frames of a grey picture (``bright``) with a white square moving 3 px a frame."""
    out = []
    for k in range(n):
        img = np.full((72, 96, 3), bright, np.uint8)
        x = x0 + 3 * k
        img[30:45, x:x + 12] = 255
        out.append(img)
    return out


def test_a_discontinuity_resets_the_models_and_ends_the_tracks():
    from dataclasses import replace as dc_replace

    from motiontrack.pipeline import Pipeline
    from motiontrack.types import Discontinuity, Frame

    cfg = load_config(None, ["motion.warmup=3", "tracker.confirm_hits=2"])
    images = _square_frames(20, 60) + _square_frames(6, 160)   # the picture jumps at frame 20
    pipe = Pipeline(cfg, (96, 72), fps=25.0)
    frames = [Frame(index=k, image=img, timestamp=k / 25.0) for k, img in enumerate(images)]
    frames[20] = dc_replace(frames[20], discontinuity=Discontinuity("loop"))
    results = list(pipe.results(frames))
    before = {t.id for r in results[:20] for t in r.tracks}
    assert before and results[19].tracks                  # the square is tracked
    # after the jump: the models learn the new picture afresh (warm-up: no regions for 3
    # frames, instead of the whole changed picture as one region), and no track of the frames
    # before it goes on
    assert results[20].discontinuity == Discontinuity("loop")
    assert [len(r.regions) for r in results[20:23]] == [0, 0, 0]
    assert not any(r.tracks for r in results[20:23])
    after = {t.id for r in results[23:] for t in r.tracks}
    assert after and not after & before and min(after) > max(before)
    # the same reset by hand: new models, no tracks, the warm-up counted from here
    detector = pipe.detector
    pipe.reset(Discontinuity("seek"))
    assert pipe.detector is not detector and pipe.tracker.active_count == 0
    assert pipe._warm_from == pipe.frames_seen == 26
