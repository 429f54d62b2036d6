"""`motiontrack track --detections det.txt` without a SOURCE, and `--detections-folder SPLIT`:
public detections tracked without the images, then scored by `evaluate --trackers-folder`."""

from __future__ import annotations

import json
import shutil

import pytest

from motiontrack.cli import main
from motiontrack.io.mot import read_mot

from helpers import require


@pytest.fixture
def mot15():
    return require("mot15-dev", "TUD-Campus", "det", "det.txt").parents[2]


def _summary(out):
    return json.loads((out / "summary.json").read_text())


def test_detections_without_a_source_take_the_sequence_from_seqinfo(tmp_path, mot15):
    seq = mot15 / "TUD-Campus"
    out = tmp_path / "o"
    assert main(["track", "--detections", str(seq / "det" / "det.txt"), "-o", str(out),
                 "--gt", str(seq / "gt" / "gt.txt")]) == 0
    s = _summary(out)
    # seqinfo.ini in the folder above det/: imWidth 640, imHeight 480, frameRate 25, seqLength 71
    assert (s["source"], s["width"], s["height"], s["source_fps"], s["frames"]) == \
        ("TUD-Campus", 640, 480, 25.0, 71)
    assert not list(out.glob("annotated*"))            # no pictures: no video
    tracks = read_mot(out / "tracks.txt")
    assert len(tracks) > 200 and tracks.frames.max() <= 71
    # the detections preset was chosen: SORT's MOTA on this sequence is 0.627
    assert s["accuracy"]["MOTA"] > 0.627
    assert 'method = "detections"' in (out / "config.toml").read_text()


def test_size_and_fps_options_stand_in_for_a_missing_seqinfo(tmp_path, mot15):
    det = tmp_path / "det.txt"
    rows = (mot15 / "TUD-Campus" / "det" / "det.txt").read_text().splitlines()
    det.write_text("\n".join(r for r in rows if int(r.split(",")[0]) <= 20) + "\n")
    out = tmp_path / "o"
    assert main(["track", "--detections", str(det), "--size", "320x240", "--fps", "10",
                 "-o", str(out)]) == 0
    s = _summary(out)
    # no seqLength: the sequence ends at the last detection's frame, 20
    assert (s["width"], s["height"], s["source_fps"], s["frames"]) == (320, 240, 10.0, 20)


def test_scene_analytics_of_detections_without_pictures_draw_the_heatmap_on_black(tmp_path, mot15):
    scene = tmp_path / "scene.toml"
    scene.write_text('[[line]]\nname = "door"\npoints = [[100, 100], [500, 400]]\n')
    out = tmp_path / "o"
    assert main(["track", "--detections", str(mot15 / "TUD-Campus" / "det" / "det.txt"),
                 "--scene", str(scene), "-o", str(out)]) == 0
    heat = _summary(out)["heatmap"]
    assert heat["background"] == "none" and heat["visits"] > 0
    assert (out / "heatmap.png").is_file() and (out / "events.jsonl").is_file()


def test_a_preset_given_with_detections_is_kept(tmp_path, mot15):
    out = tmp_path / "o"
    assert main(["track", "--detections", str(mot15 / "TUD-Campus" / "det" / "det.txt"),
                 "--preset", "fast", "--max-frames", "5", "-o", str(out)]) == 0
    assert 'method = "kalman"' in (out / "config.toml").read_text()


def test_detections_folder_writes_the_layout_evaluate_reads(tmp_path, mot15, capsys):
    data = tmp_path / "trackers" / "motiontrack" / "data"
    assert main(["track", "--detections-folder", str(mot15), "-o", str(data)]) == 0
    assert sorted(p.name for p in data.glob("*.txt")) == \
        ["ETH-Sunnyday.txt", "KITTI-17.txt", "TUD-Campus.txt"]
    assert (data / "config.toml").is_file()
    scores = tmp_path / "scores.json"
    assert main(["evaluate", "--gt-folder", str(mot15), "--trackers-folder",
                 str(tmp_path / "trackers"), "--json", str(scores)]) == 0
    res = json.loads(scores.read_text())["motiontrack"]
    assert sorted(res) == ["COMBINED", "ETH-Sunnyday", "KITTI-17", "TUD-Campus"]
    # SORT's published MOTA over the three (its README: 1 - (372 FP + 756 FN + 37 IDs) / 2900)
    assert res["COMBINED"]["MOTA"] > 1 - (372 + 756 + 37) / 2900
    # a second run into the same folder needs --force
    capsys.readouterr()
    assert main(["track", "--detections-folder", str(mot15), "-o", str(data)]) != 0
    assert "--force" in capsys.readouterr().err


def _split_with(tmp_path, mot15, det_text=None, seqinfo=True):
    split = tmp_path / "split"
    seq = split / "TUD-Campus"
    (seq / "det").mkdir(parents=True)
    if seqinfo:
        shutil.copy(mot15 / "TUD-Campus" / "seqinfo.ini", seq / "seqinfo.ini")
    (seq / "det" / "det.txt").write_text(
        det_text if det_text is not None
        else (mot15 / "TUD-Campus" / "det" / "det.txt").read_text())
    return split, seq / "det" / "det.txt"


@pytest.mark.parametrize("case, message", [
    ("no seqinfo", "no seqinfo.ini beside"),
    ("bad size", "--size must be WIDTHxHEIGHT"),
    ("malformed", "det.txt:2: expected at least 6 comma-separated values"),
    ("past the end", "detection at frame 72, beyond the sequence's seqLength 71"),
    ("empty split", "no sequences with detections in"),
    ("nothing to track", "track needs a SOURCE, or --detections det.txt"),
    ("split and source", "--detections-folder tracks a whole split"),
    ("split without -o", "--detections-folder needs -o DIR"),
    ("save without pictures", "--save draws on the source's pictures"),
    ("split with --gt", "--gt is an option of one run; --detections-folder writes"),
])
def test_bad_detection_input_is_one_clear_line(tmp_path, mot15, capsys, case, message):
    out = ["-o", str(tmp_path / "o")]
    if case == "no seqinfo":
        _, det = _split_with(tmp_path, mot15, seqinfo=False)
        args = ["--detections", str(det), *out]
    elif case == "bad size":
        _, det = _split_with(tmp_path, mot15, seqinfo=False)
        args = ["--detections", str(det), "--size", "640by480", *out]
    elif case == "malformed":
        _, det = _split_with(tmp_path, mot15, "1,-1,10,10,5,5,0.9\n2,-1,oops\n")
        args = ["--detections", str(det), *out]
    elif case == "past the end":
        _, det = _split_with(tmp_path, mot15, "72,-1,10,10,5,5,0.9,-1,-1,-1\n")
        args = ["--detections", str(det), *out]
    elif case == "empty split":
        (tmp_path / "empty" / "SEQ").mkdir(parents=True)
        args = ["--detections-folder", str(tmp_path / "empty"), *out]
    elif case == "nothing to track":
        args = out
    elif case == "save without pictures":
        args = ["--detections", str(mot15 / "TUD-Campus" / "det" / "det.txt"), "--save",
                "background", *out]
    elif case == "split with --gt":
        args = ["--detections-folder", str(mot15), "--gt", str(mot15 / "TUD-Campus" / "gt" /
                                                               "gt.txt"), *out]
    elif case == "split and source":
        args = ["synth:walker", "--detections-folder", str(mot15), *out]
    else:
        args = ["--detections-folder", str(mot15)]
    code = main(["track", *args])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and err[0].startswith("motiontrack: error:"), err
    assert message in err[0]


def test_a_motion_blob_tracker_key_set_with_detections_is_warned_about(tmp_path, mot15, capsys):
    assert main(["track", "--detections", str(mot15 / "TUD-Campus" / "det" / "det.txt"),
                 "--set", "tracker.min_iou=0.2", "--max-frames", "3", "-o", str(tmp_path / "o")]) == 0
    err = capsys.readouterr().err
    assert "tracker.min_iou has no effect while tracker.method = detections" in err, err
