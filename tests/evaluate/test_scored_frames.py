"""Scores cover the frames the ground truth covers (motiontrack.evaluate.score.scored_frames):
predictions past the ground truth are left out, and one line says so."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from motiontrack.cli import main
from motiontrack.evaluate.score import score_run, scored_frames
from motiontrack.io.annotations import read_ground_truth
from motiontrack.io.mot import read_mot, write_mot
from motiontrack.synth import make_scene
from motiontrack.types import Annotations


def _extended(gt: Annotations, last: int) -> Annotations:
    """A perfect tracker on the ground truth's frames 1-300 that goes on to frame ``last``:
    frame f > 300 holds the boxes of frame (f - 1) % 300 + 1 under new ids."""
    gt = gt.select(gt.consider)
    f = np.arange(301, last + 1)
    src = (f - 1) % 300 + 1
    rows = [np.flatnonzero(gt.frames == s) for s in src]
    idx = np.concatenate(rows)
    frames = np.concatenate([np.full(len(r), k) for k, r in zip(f, rows)])
    return Annotations.from_columns(np.concatenate([gt.frames, frames]),
                                    np.concatenate([gt.ids, gt.ids[idx] + 1000]),
                                    np.concatenate([gt.boxes, gt.boxes[idx]]))


def test_a_run_is_scored_over_the_processed_frames_the_ground_truth_covers():
    gt = make_scene("walker", n_frames=60, width=320, height=240).ground_truth()
    assert gt.meta["seq_length"] == 60          # a scene annotates every one of its frames
    pred = gt.select(gt.consider)               # perfect over frames 1-60
    # ground truth of frames up to 40 from a file: it covers its first to its last frame
    first = int(gt.frames.min())
    acc = score_run(replace(gt.select(gt.frames <= 40), meta={}), pred, frames=60)
    assert (acc["MOTA"], acc["FP"]) == (1.0, 0)
    assert acc["frames_scored"] == [first, 40]
    assert acc["left_out_frames"] == 20
    acc = score_run(gt, pred, frames=60)
    assert acc["frames_scored"] == [1, 60] and "left_out_frames" not in acc
    # --start 9 --max-frames 20: frames 10-29, inside the ground truth: nothing left out
    acc = score_run(gt, pred.select(pred.frames <= 29), frames=20, start=9)
    assert "left_out_frames" not in acc


def test_scored_frames_handles_empty_tables():
    empty = Annotations.empty()
    g, p, w = scored_frames(empty, empty)
    assert (len(g), len(p), w.note()) == (0, 0, "")


@pytest.fixture
def pets_pred(data, tmp_path) -> tuple[Path, Path]:
    gt_path = data("pets09-s2l1", "gt_mot15.txt")
    pred = tmp_path / "tracks.txt"
    write_mot(_extended(read_mot(gt_path, kind="gt"), 795), pred, kind="results")
    return gt_path, pred


def _evaluate(capsys, *args: str) -> tuple[dict, str]:
    assert main(["evaluate", "--metrics", "clear,identity,hota", "--json", "-", *args]) == 0
    out = capsys.readouterr()
    return json.loads(out.out), out.err


@pytest.mark.data
def test_evaluate_scores_only_the_frames_the_ground_truth_covers(pets_pred, capsys):
    gt, pred = pets_pred
    m, err = _evaluate(capsys, "--gt", str(gt), "--pred", str(pred))
    assert (m["MOTA"], m["HOTA"], m["FP"]) == (1.0, 1.0, 0)   # the perfect frames 1-300
    assert ("scored frames 1–300 of the ground truth; 495 predicted frames outside it" in err)


@pytest.mark.data
def test_score_outside_gt_counts_them_as_false_positives(pets_pred, capsys):
    gt, pred = pets_pred
    m, err = _evaluate(capsys, "--gt", str(gt), "--pred", str(pred), "--score-outside-gt")
    outside = read_mot(pred).frames > 300
    assert m["FP"] == np.count_nonzero(outside) and m["MOTA"] < 0
    assert "left out" not in err


@pytest.mark.data
def test_frames_narrows_within_the_ground_truth(pets_pred, capsys):
    gt, pred = pets_pred
    m, err = _evaluate(capsys, "--gt", str(gt), "--pred", str(pred), "--frames", "201:400")
    assert (m["MOTA"], m["FP"]) == (1.0, 0)
    assert "scored frames 201–300 of the ground truth; 100 predicted frames" in err
    _, err = _evaluate(capsys, "--gt", str(gt), "--pred", str(pred), "--frames", "1:300")
    assert "left out" not in err           # nothing outside the frames asked for was dropped
    assert main(["evaluate", "--gt", str(gt), "--pred", str(pred), "--frames", "400:500"]) == 2
    assert "holds none of the ground truth's frames 1–300" in capsys.readouterr().err


@pytest.mark.data
def test_a_seqinfo_beside_the_ground_truth_sets_the_frames_covered(pets_pred, tmp_path, capsys):
    gt, pred = pets_pred
    seq = tmp_path / "PETS"
    (seq / "gt").mkdir(parents=True)
    (seq / "gt" / "gt.txt").write_bytes(Path(gt).read_bytes())
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=PETS\nseqLength=350\n")
    assert read_ground_truth(seq / "gt" / "gt.txt").meta["seq_length"] == 350
    m, err = _evaluate(capsys, "--gt", str(seq / "gt" / "gt.txt"), "--pred", str(pred))
    assert m["FP"] == np.count_nonzero((read_mot(pred).frames > 300)
                                       & (read_mot(pred).frames <= 350))
    assert "scored frames 1–350 of the ground truth's sequence; 445 predicted frames" in err


def test_track_gt_scores_the_frames_its_ground_truth_covers(tmp_path, capsys):
    source = "synth:walker?n_frames=60&width=320&height=240"
    gt = make_scene("walker", n_frames=60, width=320, height=240).ground_truth()
    write_mot(gt.select(gt.frames <= 40), tmp_path / "gt40.txt", kind="gt")
    assert main(["track", source, "--no-video", "--gt", str(tmp_path / "gt40.txt"),
                 "-o", str(tmp_path / "run")]) == 0
    acc = json.loads((tmp_path / "run" / "summary.json").read_text())["accuracy"]
    tracks = read_mot(tmp_path / "run" / "tracks.txt")
    later = np.unique(tracks.frames[tracks.frames > 40])
    assert len(later) > 10 and acc["left_out_frames"] == len(later)
    assert acc["frames_scored"] == [int(gt.frames.min()), 40]
    assert f"{len(later)} predicted frames outside it" in capsys.readouterr().err
