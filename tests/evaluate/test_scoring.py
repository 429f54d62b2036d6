"""Scoring conventions for zero-marked ground truth (``--scoring``): one default (TrackEval's
MOTChallenge convention) on every path that scores tracks, the other behind the same option,
every score naming its convention; and the ``evaluate`` table's one format per column."""

from __future__ import annotations

import json

import pytest

from helpers import ann
from motiontrack.cli import main
from motiontrack.cli.evaluate import evaluate_one, format_table
from motiontrack.errors import ConfigError
from motiontrack.evaluate.score import score_run
from motiontrack.evaluate.scoring import DEFAULT_SCORING, SCORING

#: the metrics `track --gt` writes to summary.json, all of which `evaluate` reports too
SHARED_KEYS = ("HOTA", "MOTA", "IDF1", "MOTP", "DetA", "AssA", "IDSW", "TP", "FP", "FN",
               "recall", "precision")

# one frame, 10 x 10 boxes
GT = [(1, 1, 0, 0, 10, 10, 1, -1),      # a person that counts
      (1, 2, 50, 0, 10, 10, 0, -1)]     # a person marked zero (outside the area, occluded, ...)
PRED = [(1, 5, 0, 0, 10, 10),           # on person 1: a hit
        (1, 6, 51, 0, 10, 10)]          # on the zero-marked person: IoU 90 / 110 >= 0.5
EXPECTED = {
    # the zero-marked row is dropped, the box on it stays: 1 hit, 1 false positive
    "trackeval": {"TP": 1, "FP": 1, "FN": 0, "MOTA": 1 - (0 + 1 + 0) / 1, "precision": 1 / 2},
    # the box on the zero-marked row is dropped with it: 1 hit, nothing else
    "ignore-regions": {"TP": 1, "FP": 0, "FN": 0, "MOTA": 1.0, "precision": 1.0},
}


def test_the_default_is_trackevals_convention():
    assert DEFAULT_SCORING == "trackeval"
    assert set(SCORING) == set(EXPECTED)


@pytest.mark.parametrize("scoring", list(EXPECTED))
def test_box_on_zero_marked_gt_counts_as_the_convention_says_on_both_paths(scoring):
    gt, pred = ann(GT, gt=True), ann(PRED)
    run = score_run(gt, pred, frames=1, scoring=scoring)                  # track --gt
    flat, _, _ = evaluate_one(gt, pred, ("clear", "identity", "hota"), 0.75, scoring=scoring)
    for key, value in EXPECTED[scoring].items():
        assert run[key] == pytest.approx(value), key
        assert flat[key] == pytest.approx(value), key
    assert run["scoring"] == flat["scoring"] == scoring


def test_default_scoring_of_a_run_counts_the_box_on_zero_marked_gt():
    run = score_run(ann(GT, gt=True), ann(PRED), frames=1)
    assert run["FP"] == 1 and run["scoring"] == "trackeval"


@pytest.mark.parametrize("scoring", list(EXPECTED))
def test_evaluate_command_json_per_frame_and_table_name_the_convention(tmp_path, capsys, scoring):
    gt, pred = tmp_path / "gt.txt", tmp_path / "pred.txt"
    gt.write_text("".join(",".join(map(str, r)) + ",-1,-1\n" for r in GT))
    pred.write_text("".join(",".join(map(str, r)) + ",1,-1,-1,-1\n" for r in PRED))
    out, pf = tmp_path / "m.json", tmp_path / "pf.csv"
    assert main(["evaluate", "--gt", str(gt), "--pred", str(pred), "--scoring", scoring,
                 "--metrics", "clear,identity,hota", "--json", str(out),
                 "--per-frame", str(pf)]) == 0
    res = json.loads(out.read_text())
    assert res["scoring"] == scoring and res["FP"] == EXPECTED[scoring]["FP"]
    header, row = pf.read_text().splitlines()
    assert dict(zip(header.split(","), row.split(",")))["scoring"] == scoring
    assert f"scoring {scoring}:" in capsys.readouterr().out.splitlines()[-1]


def test_evaluate_without_scoring_option_uses_trackeval(tmp_path, capsys):
    gt, pred = tmp_path / "gt.txt", tmp_path / "pred.txt"
    gt.write_text("".join(",".join(map(str, r)) + ",-1,-1\n" for r in GT))
    pred.write_text("".join(",".join(map(str, r)) + ",1,-1,-1,-1\n" for r in PRED))
    assert main(["evaluate", "--gt", str(gt), "--pred", str(pred), "--metrics", "clear",
                 "--json", "-"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["scoring"] == "trackeval" and res["FP"] == 1


def test_unknown_scoring_is_a_user_error(tmp_path, capsys):
    with pytest.raises(ConfigError, match="unknown scoring 'mot15'; valid: trackeval, ignore-regions"):
        score_run(ann(GT, gt=True), ann(PRED), frames=1, scoring="mot15")
    with pytest.raises(SystemExit) as exc:
        main(["evaluate", "--gt", "g.txt", "--pred", "p.txt", "--scoring", "mot15"])
    assert exc.value.code == 2
    assert "invalid choice: 'mot15'" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["track", "evaluate", "flow", "sweep", "tune", "ablate"])
def test_every_scoring_command_has_the_same_option(command, capsys):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--scoring {trackeval,ignore-regions}" in text
    assert "trackeval (default): TrackEval's MOTChallenge convention" in text


# --------------------------------------------------------------------------------------------------
# the evaluate table: one format per column
# --------------------------------------------------------------------------------------------------
def test_table_prints_a_ratio_column_in_percent_whatever_the_value_and_counts_as_integers():
    results = {
        "good": {"MOTA": 0.75, "IDF1": 1.0, "IDSW": 3, "FP": 2.0, "scoring": "trackeval"},
        # 10 gt boxes, 35 false positives: MOTA = 1 - (0 + 35 + 0) / 10 = -2.5
        "noisy": {"MOTA": 1 - 35 / 10, "IDF1": 0.125, "IDSW": 0, "FP": 35, "scoring": "trackeval"},
        "empty": {"MOTA": float("nan"), "IDF1": 0.0, "IDSW": 0, "FP": 0, "scoring": "trackeval"},
    }
    lines = format_table(results).splitlines()
    assert lines[0].split() == ["tracker", "MOTA", "IDF1", "IDSW", "FP"]
    assert lines[2].split() == ["good", "75.00", "100.00", "3", "2"]
    assert lines[3].split() == ["noisy", "-250.00", "12.50", "0", "35"]
    assert lines[4].split() == ["empty", "-", "0.00", "0", "0"]
    assert lines[5].startswith("ratios in percent; scoring trackeval: zero-marked gt rows dropped")


def test_table_without_tracking_metrics_names_no_scoring():
    lines = format_table({"t": {"pixel_precision": 0.5}}).splitlines()
    assert lines[-1].split() == ["t", "50.00"]


# --------------------------------------------------------------------------------------------------
# the same numbers from `track --gt` and `evaluate`, on real footage
# --------------------------------------------------------------------------------------------------
@pytest.mark.data
@pytest.mark.slow
def test_track_and_evaluate_give_the_same_accuracy_on_pets_in_each_convention(data, tmp_path,
                                                                               capsys):
    # frames 141-220 hold people marked zero in gt_mot15.txt (outside the annotated area), so
    # the conventions differ there
    video, gt = data("pets09-s2l1", "video.avi"), data("pets09-s2l1", "gt_mot15.txt")
    acc = {}
    for scoring in SCORING:
        out = tmp_path / scoring
        assert main(["track", str(video), "--gt", str(gt), "--start", "140", "--max-frames", "80",
                     "--no-video", "-o", str(out), "--scoring", scoring]) == 0
        printed = capsys.readouterr().out
        acc[scoring] = json.loads((out / "summary.json").read_text())["accuracy"]
        assert acc[scoring]["scoring"] == scoring
        assert f"(scoring {scoring})" in next(ln for ln in printed.splitlines()
                                             if ln.startswith("accuracy"))
        assert main(["evaluate", "--gt", str(gt), "--pred", str(out / "tracks.txt"),
                     "--frames", "141:220", "--metrics", "clear,identity,hota",
                     "--scoring", scoring, "--json", "-"]) == 0
        res = json.loads(capsys.readouterr().out)
        assert res["scoring"] == scoring
        for key in SHARED_KEYS:
            assert acc[scoring][key] == pytest.approx(res[key], abs=1e-12), (scoring, key)
    # the same tracks (a run repeats exactly), scored two ways: the boxes on zero-marked people
    # are false positives under trackeval only
    assert (tmp_path / "trackeval" / "tracks.txt").read_bytes() == \
        (tmp_path / "ignore-regions" / "tracks.txt").read_bytes()
    assert acc["trackeval"]["FP"] > acc["ignore-regions"]["FP"]
    assert acc["trackeval"]["MOTA"] < acc["ignore-regions"]["MOTA"]


# --------------------------------------------------------------------------------------------------
# studies
# --------------------------------------------------------------------------------------------------
def test_study_records_its_scoring_and_a_study_without_one_replays_with_ignore_regions():
    from motiontrack.config import load_config
    from motiontrack.studies.sweep import Study, study_from_args

    st = study_from_args(["synth:walker"], None, ["tracker.backfill=true,false"],
                         load_config(None))
    assert st.scoring == "trackeval"
    meta = st.as_dict()
    assert meta["evaluation"]["scoring"] == "trackeval"
    assert all(spec.scoring == "trackeval" for spec in st.specs())
    other = study_from_args(["synth:walker"], None, ["tracker.backfill=true"], load_config(None),
                            scoring="ignore-regions")
    assert Study.from_dict(other.as_dict()).scoring == "ignore-regions"
    del meta["evaluation"]["scoring"]
    assert Study.from_dict(meta).scoring == "ignore-regions"
    with pytest.raises(ConfigError, match="unknown scoring"):
        study_from_args(["synth:walker"], None, ["tracker.backfill=true"], load_config(None),
                        scoring="nope")


@pytest.mark.slow
def test_sweep_scores_each_run_in_the_studys_convention(tmp_path):
    from motiontrack.config import load_config, to_dict
    from motiontrack.io.mot import read_mot
    from motiontrack.io.manifest import SequenceSpec
    from motiontrack.studies.sweep import RunSpec, execute_run
    from motiontrack.synth import parse_synth_spec

    # the person behind the column is marked zero while mostly hidden, and the tracker keeps a
    # box on them for part of that time
    seq = SequenceSpec("column", "synth:column")
    gt = parse_synth_spec("synth:column").ground_truth()
    rows = {}
    for scoring in SCORING:
        res = execute_run(RunSpec(run=1, params=(), sequence=seq,
                                  base_config=to_dict(load_config(None)), scoring=scoring))
        row = rows[scoring] = res["row"]
        (text,) = [t for name, t in res["files"].items() if name.endswith("/tracks.txt")]
        (tmp_path / f"{scoring}.txt").write_text(text)
        tracks = read_mot(tmp_path / f"{scoring}.txt", kind="results")
        run = score_run(gt, tracks, row["frames"], scoring=scoring)   # as `track --gt` scores
        for key in ("HOTA", "MOTA", "IDF1", "TP", "FP", "FN", "IDSW"):
            assert row[key] == pytest.approx(run[key], abs=1e-12), (scoring, key)
    assert rows["trackeval"]["FP"] > rows["ignore-regions"]["FP"]


def test_ablation_table_and_rows_name_the_scoring():
    from motiontrack.studies.ablate import COLUMNS, format_table as ablation_table

    row = {"configuration": "base", **{c: 0.5 for c in COLUMNS}, "scoring": "trackeval"}
    assert ablation_table([row]).splitlines()[-1] == "scoring trackeval"
