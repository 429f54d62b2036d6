"""Parameter studies: grid parsing, monotone recall, executors give identical tables, replay."""

from __future__ import annotations

import json
import math

import pytest

from motiontrack.config import PipelineConfig, load_config
from motiontrack.errors import ConfigError, InputError
from motiontrack.io.manifest import SequenceSpec, read_manifest
from motiontrack.studies.params import parse_param
from motiontrack.studies.sweep import Study, load_study, run_sweep, study_from_args
from motiontrack.studies.table import read_table, summarise_runs, write_table

SCENE = "synth:walker?n_frames=80"


@pytest.mark.parametrize("text, key, values", [
    ("motion.median.threshold=0.05,0.1,0.2", "motion.median.threshold", (0.05, 0.1, 0.2)),
    ("regions.min_size=0:0.3:0.1", "regions.min_size", (0.0, 0.1, 0.2, 0.3)),   # no float drift
    ("regions.min_area=100:300:100", "regions.min_area", (100, 200, 300)),       # ints stay ints
    ("regions.min_area=1:6:2", "regions.min_area", (1, 3, 5)),                   # b not on the grid
    ("motion.method=mog2,knn", "motion.method", ("mog2", "knn")),                # bare strings
    ("motion.mog2.detect_shadows=true,false", "motion.mog2.detect_shadows", (True, False)),
    (" a.b = 3 ", "a.b", (3,)),
])
def test_parse_param(text, key, values):
    k, v = parse_param(text)
    assert k == key
    assert v == values
    assert [type(x) for x in v] == [type(x) for x in values]


@pytest.mark.parametrize("text", [
    "motion.median.threshold",      # no '='
    "motion.median.threshold=",     # no values
    "=1,2",                         # no key
    "a..b=1",                       # empty key part
    "a.b=1:2",                      # range without step
    "a.b=2:1:1",                    # b < a
    "a.b=0:1:0",                    # zero step
    "a.b=x:1:0.5",                  # not a number
    "a.b=1,,2",                     # empty value
    "a.b=1,1",                      # repeated value
])
def test_parse_param_rejects(text):
    with pytest.raises(ConfigError):
        parse_param(text)


@pytest.mark.parametrize("grid, match", [
    ((("motion.median.nope", (1,)),), "unknown config key"),
    ((("motion.median.threshold", (2.0,)),), "must be in"),      # outside [0, 1]
    ((("motion.median.threshold", (0.1,)), ("motion.median.threshold", (0.2,))), "distinct"),
])
def test_study_validates_every_grid_point_before_running(grid, match):
    with pytest.raises(ConfigError, match=match):
        Study(sequences=(SequenceSpec("w", SCENE),), grid=grid,
              base_config=__import__("dataclasses").asdict(PipelineConfig()))


def test_sequence_needs_gt_unless_synthetic():
    SequenceSpec("w", SCENE)  # synthetic: its own ground truth
    with pytest.raises(ConfigError, match="--gt is required"):
        SequenceSpec("v", "video.avi")


def test_grid_order_first_parameter_slowest():
    st = study_from_args([SCENE], None, ["regions.min_area=10,20", "motion.median.threshold=0.1,0.2,0.3"],
                         load_config(None, ["motion.method=median"]))
    pts = st.points()
    assert len(pts) == 2 * 3
    assert pts[0] == (("regions.min_area", 10), ("motion.median.threshold", 0.1))
    assert pts[1] == (("regions.min_area", 10), ("motion.median.threshold", 0.2))
    assert pts[3] == (("regions.min_area", 20), ("motion.median.threshold", 0.1))


def test_manifest(tmp_path):
    (tmp_path / "gt.txt").write_text("1,1,10,10,5,5,1,-1,-1,-1\n")
    m = tmp_path / "seqs.toml"
    m.write_text('[[sequence]]\nname = "a"\nsource = "synth:walker?n_frames=10"\ngroup = "synthetic"\n'
                 '[[sequence]]\nsource = "clip.avi"\ngt = "gt.txt"\n')
    seqs = read_manifest(m)
    assert [s.name for s in seqs] == ["a", "clip"]
    assert seqs[0].gt is None and seqs[0].group == "synthetic"
    assert seqs[1].source == str((tmp_path / "clip.avi").resolve())   # relative to the manifest
    assert seqs[1].gt == str((tmp_path / "gt.txt").resolve())
    bad = tmp_path / "bad.toml"
    bad.write_text('[[sequence]]\nsource = "synth:walker"\ncolour = 1\n')
    with pytest.raises(InputError, match="unknown key"):
        read_manifest(bad)


def test_table_round_trip_and_summary(tmp_path):
    rows = [{"run": 1, "sequence": "a", "group": "", "p": 0.1, "m": 0.5, "x": float("nan")},
            {"run": 1, "sequence": "b", "group": "", "p": 0.1, "m": 0.25, "x": 2.0},
            {"run": 2, "sequence": "a", "group": "", "p": 0.2, "m": 1 / 3, "x": float("nan")}]
    write_table(rows, tmp_path / "t.csv")
    back = read_table(tmp_path / "t.csv")
    assert back[2]["m"] == 1 / 3            # repr round trip is exact
    assert math.isnan(back[0]["x"])
    summ = summarise_runs(back, ["p"])
    assert [s["run"] for s in summ] == [1, 2]
    assert summ[0]["m"] == (0.5 + 0.25) / 2
    assert summ[0]["x"] == 2.0               # nan-aware mean
    assert summ[0]["sequences"] == 2


# ------------------------------------------------------------------------- real runs (synthetic)
THRESHOLDS = (0.02, 0.1, 0.2, 0.3, 0.4)


@pytest.fixture(scope="module")
def threshold_sweep(tmp_path_factory):
    """Serial sweep of the temporal-median threshold (DETECT_DIFF_THRESH) on a short walker scene."""
    out = tmp_path_factory.mktemp("sweep_serial")
    st = study_from_args([SCENE], None, ["motion.median.threshold=" + ",".join(map(str, THRESHOLDS))],
                         load_config(None, ["motion.method=median"]))
    res = run_sweep(st, out, jobs=1, figures=False)  # figures: test_overlay_report.py
    return st, out, res


@pytest.mark.parametrize("col", ["det_pixel_recall", "det_object_area_recall",
                                 "det_localized_object_recall"])
@pytest.mark.slow
def test_recall_never_rises_with_the_motion_threshold(threshold_sweep, col):
    # The median background does not depend on the threshold, so a higher threshold gives a subset
    # mask; median filter, erosion and dilation are increasing operators and a region of the smaller
    # mask lies inside one of the larger, so the union of region boxes (and every recall) shrinks.
    _, _, res = threshold_sweep
    rows = sorted(res.rows, key=lambda r: r["motion.median.threshold"])
    rec = [r[col] for r in rows]
    assert all(b <= a for a, b in zip(rec, rec[1:])), rec
    assert rec[0] > rec[-1] + 0.2, rec      # the sweep really spans the interesting range


@pytest.mark.slow
def test_sweep_outputs(threshold_sweep):
    st, out, res = threshold_sweep
    assert [r["run"] for r in res.rows] == [1, 2, 3, 4, 5]
    assert [r["motion.median.threshold"] for r in res.rows] == list(THRESHOLDS)
    assert all(r["frames"] == 80 for r in res.rows)
    for name in ("study.json", "results.csv", "summary.csv", "config.toml",
                 "runs/r001/walker/tracks.txt", "runs/r005/walker/regions.txt"):
        assert (out / name).is_file(), name
    meta = json.loads((out / "study.json").read_text())
    assert meta["grid"] == [{"key": "motion.median.threshold", "values": list(THRESHOLDS)}]
    assert meta["base_config"]["motion"]["method"] == "median"
    assert {"motiontrack", "opencv", "numpy", "python"} <= set(meta["versions"])
    assert read_table(out / "results.csv") == res.rows


@pytest.fixture(scope="module")
def small_sweep(tmp_path_factory):
    """A short serial sweep (3 runs) the other executors are compared with."""
    out = tmp_path_factory.mktemp("sweep_small")
    st = study_from_args(["synth:walker?n_frames=40"], None, ["motion.median.threshold=0.05,0.2,0.35"],
                         load_config(None, ["motion.method=median"]))
    run_sweep(st, out, jobs=1, figures=False)
    return st, out


@pytest.mark.slow
def test_parallel_and_serial_tables_are_identical(small_sweep, tmp_path):
    st, out = small_sweep
    run_sweep(st, tmp_path, jobs=2, figures=False)
    assert (tmp_path / "results.csv").read_bytes() == (out / "results.csv").read_bytes()
    assert ((tmp_path / "runs/r002/walker/tracks.txt").read_bytes()
            == (out / "runs/r002/walker/tracks.txt").read_bytes())


@pytest.mark.slow
def test_replay_reproduces_the_study(threshold_sweep):
    st, out, _ = threshold_sweep
    study, meta = load_study(out)
    assert study == st                       # same sequences, grid, base config, xi, save
    assert meta["runs"] == len(THRESHOLDS)
    # rerunning it gives the identical table: see test_cli_two_parameters_and_intermediate_movies


@pytest.mark.slow
def test_dask_local_cluster_gives_the_same_table(small_sweep, tmp_path, dask_session_client):
    st, out = small_sweep
    run_sweep(st, tmp_path, cluster=dask_session_client.scheduler.address, figures=False)
    assert (tmp_path / "results.csv").read_bytes() == (out / "results.csv").read_bytes()


@pytest.mark.slow
def test_existing_study_is_not_overwritten(threshold_sweep):
    st, out, _ = threshold_sweep
    with pytest.raises(InputError, match="--force"):
        run_sweep(st, out, figures=False)


@pytest.mark.slow
def test_cli_two_parameters_and_intermediate_movies(tmp_path, capsys):
    from motiontrack.cli import main

    out = tmp_path / "study"
    code = main(["-q", "sweep", "synth:walker?n_frames=30", "--set", "motion.method=median",
                 "--param", "motion.median.threshold=0.1,0.3", "--param", "regions.min_area=50,400",
                 "--save", "background,difference,motion", "--set", "output.codec=mjpg",
                 "-o", str(out)])
    assert code == 0
    rows = read_table(out / "results.csv")
    assert len(rows) == 2 * 2
    assert {(r["motion.median.threshold"], r["regions.min_area"]) for r in rows} == {
        (0.1, 50), (0.1, 400), (0.3, 50), (0.3, 400)}
    for f in ("pr_map_regions.png", "pr_map_regions.svg", "pr_regions.svg", "pr_map_tracks.svg",
              "hota_map.svg"):
        assert (out / "figures" / f).is_file(), f
    for s in ("background", "difference", "motion"):
        assert (out / "runs/r001/walker" / f"{s}.avi").stat().st_size > 0
    # replay through the CLI reports the identical table
    code = main(["-q", "sweep", "--replay", str(out), "--no-figures", "-o", str(tmp_path / "again")])
    assert code == 0
    assert "identical to" in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["sweep", "synth:walker", "-o", "X"], "at least one --param"),
    (["sweep", "--replay", "X", "--scoring", "ignore-regions", "-o", "Y"], "--scoring with it"),
    (["sweep", "synth:walker", "--param", "motion.nope=1", "-o", "X"], "unknown config key"),
    (["sweep", "video.avi", "--param", "regions.min_area=1", "-o", "X"], "--gt is required"),
    (["sweep", "synth:walker", "--param", "regions.min_area=1", "--save", "colour", "-o", "X"],
     "unknown --save"),
])
def test_cli_errors_are_one_line(argv, message, capsys, tmp_path, monkeypatch):
    from motiontrack.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(argv) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err


# ------------------------------------------------------------------------- intermediate movies
@pytest.mark.parametrize("text, expected", [
    ("background,difference,motion", ("background", "difference", "motion")),
    ("motion, ,motion,annotated", ("motion", "annotated")),       # blanks and repeats dropped
    ("", ()),
])
def test_parse_streams(text, expected):
    from motiontrack.render.streams import parse_streams

    assert parse_streams(text) == expected


def test_stream_images():
    import numpy as np

    from motiontrack.render.streams import parse_streams, stream_image
    from motiontrack.types import FrameResult

    raw = np.zeros((4, 6), np.uint8)
    raw[1, 2] = 255
    mask = np.zeros((4, 6), np.uint8)
    res = FrameResult(index=0, timestamp=0.0, frame=np.zeros((8, 12, 3), np.uint8), mask=mask,
                      regions=(), tracks=(), raw_mask=raw)

    assert (stream_image("difference", res) == raw).all()
    assert (stream_image("motion", res) == mask).all()
    assert stream_image("background", res, None).shape == (4, 6)       # no model: black frame
    assert stream_image("background", res, None).max() == 0
    assert stream_image("background", res, np.full((4, 6), 7, np.uint8)).max() == 7
    assert stream_image("annotated", res).shape == (8, 12, 3)
    with pytest.raises(ConfigError, match="valid"):
        parse_streams("colour")


def test_intermediate_writer_with_the_pipeline(tmp_path):
    from motiontrack.pipeline import open_configured_source
    from motiontrack.run import Job
    from motiontrack.run.processors import TrackProcessor
    from motiontrack.run.writers import IntermediateWriter

    cfg = load_config(None, ["motion.method=median"])
    src = open_configured_source("synth:walker?n_frames=12", cfg.source)
    streams = ("background", "difference", "motion")
    proc = TrackProcessor(cfg, src.info, needs_background=True)
    Job(src, proc, [IntermediateWriter(tmp_path, streams, "mjpg")], tmp_path).run()
    for s in ("background", "difference", "motion"):
        assert (tmp_path / f"{s}.avi").stat().st_size > 0
    import cv2

    cap = cv2.VideoCapture(str(tmp_path / "motion.avi"))
    n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    ok, img = cap.read()
    cap.release()
    assert n == 12 and ok
    assert img.shape[:2] == (288, 384)          # automatic processing scale 0.6 of 640x480


def test_interrupted_sweep_keeps_finished_runs(tmp_path, monkeypatch, capsys):
    import json as _json

    import motiontrack.studies.sweep as sw
    from motiontrack.cli import main

    real = sw.execute_run
    calls = []

    def flaky(spec, should_stop=None):
        calls.append(spec.run)
        if len(calls) == 3:           # Ctrl-C while the third run is going
            raise KeyboardInterrupt
        return real(spec, should_stop)

    monkeypatch.setattr(sw, "execute_run", flaky)
    out = tmp_path / "study"
    code = main(["sweep", "synth:walker?n_frames=30", "--param", "motion.median.threshold=0.1,0.2,0.3,0.4",
                 "--set", "motion.method=median", "--no-figures", "-o", str(out)])
    assert code == 130
    summary = _json.loads((out / "summary.json").read_text())
    assert summary == {"status": "interrupted", "interrupted": True, "runs_done": 2, "runs": 4}
    rows = read_table(out / "results.csv")
    assert [r["motion.median.threshold"] for r in rows] == [0.1, 0.2]
    assert (out / "runs" / "r001" / "walker" / "tracks.txt").is_file()
    assert "interrupted" in capsys.readouterr().err


@pytest.mark.slow
def test_sweep_scores_what_track_writes_with_fill_motion(tmp_path):
    """With ``tracker.fill_motion`` a run's tracks gain their tentative frames and filled gaps
    when it ends; a sweep run must score (and save) the same tracks as ``motiontrack track``."""
    from motiontrack.cli import main
    from motiontrack.io.mot import read_mot

    scene = "synth:crossing?n_frames=120"
    base = ["tracker.fill_motion=true"]
    st = study_from_args([scene], None, ["tracker.backfill=true,false"], load_config(None, base))
    res = run_sweep(st, tmp_path / "sweep", jobs=1, figures=False)
    assert main(["track", scene, "--no-video", "-o", str(tmp_path / "track"),
                 *[a for b in base for a in ("--set", b)]]) == 0
    summary = json.loads((tmp_path / "track" / "summary.json").read_text())
    assert summary["backfilled_rows"] > 0
    track_rows = (tmp_path / "track" / "tracks.txt").read_text()
    sweep_rows = (tmp_path / "sweep" / "runs" / "r001" / "crossing" / "tracks.txt").read_text()
    key = lambda text: [r.split(",")[:6] for r in text.splitlines()]   # frame, id, box
    assert key(sweep_rows) == key(track_rows)
    for k in ("MOTA", "IDF1", "HOTA"):
        assert res.rows[0][k] == pytest.approx(summary["accuracy"][k], abs=1e-9), k
    # backfill off: fewer rows, so the sweep really scores the completed file
    assert len(read_mot(tmp_path / "sweep" / "runs" / "r002" / "crossing" / "tracks.txt")) \
        == len(read_mot(tmp_path / "track" / "tracks.txt")) - summary["backfilled_rows"]


def test_the_console_table_shows_whole_parameter_names_and_idf1():
    from motiontrack.studies.table import format_summary

    keys = ["motion.knn.dist2_threshold", "motion.knn.history"]
    summary = [{"run": 1, "sequences": 1, keys[0]: 300, keys[1]: 100, "det_pixel_precision": 0.8872,
                "det_pixel_recall": 0.9694, "det_object_f1": 0.8877, "HOTA": 0.672,
                "MOTA": 0.86667, "IDF1": 0.92857},
               {"run": 2, "sequences": 1, keys[0]: 600, keys[1]: 100, "det_pixel_precision": 0.9,
                "det_pixel_recall": 0.9, "det_object_f1": 0.9, "HOTA": 0.5, "MOTA": 0.5,
                "IDF1": 0.25}]
    head, one, two = format_summary(summary, keys).splitlines()
    assert head.split() == ["run", *keys, "det_pixel_precision", "det_pixel_recall",
                            "det_object_f1", "HOTA", "MOTA", "IDF1"]
    assert one.split() == ["1", "300", "100", "0.8872", "0.9694", "0.8877", "0.672", "0.8667",
                           "0.9286"]
    assert two.split()[-1] == "0.25"
    # right-aligned under each heading
    assert len(head) == len(one) == len(two) and head.index("IDF1") + 4 == len(head)


def test_summary_keeps_whole_counts_as_integers(tmp_path):
    rows = [{"run": 1, "sequence": "a", "group": "", "p": 300, "frames": 40, "n_tracks": 1},
            {"run": 1, "sequence": "b", "group": "", "p": 300, "frames": 30, "n_tracks": 3},
            {"run": 2, "sequence": "a", "group": "", "p": 600, "frames": 40, "n_tracks": 2},
            {"run": 2, "sequence": "b", "group": "", "p": 600, "frames": 30, "n_tracks": 2}]
    summ = summarise_runs(rows, ["p"])
    assert [(s["p"], s["frames"], s["n_tracks"]) for s in summ] == [(300, 35, 2), (600, 35, 2)]
    assert all(type(s["frames"]) is int for s in summ)
    write_table(summ, tmp_path / "summary.csv")
    assert (tmp_path / "summary.csv").read_text().splitlines()[1] == "1,2,300,35,2"
    odd = summarise_runs(rows[:1] + [{**rows[1], "frames": 31}], ["p"])
    assert odd[0]["frames"] == 35.5           # a mean that is no whole number stays a float
