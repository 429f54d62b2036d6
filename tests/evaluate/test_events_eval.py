"""Event-level evaluation: matching within a time tolerance, scores per group, type and total;
events files; the evaluate-events command."""

from __future__ import annotations

import json

import pytest

from motiontrack.cli import main
from motiontrack.errors import ConfigError, InputError
from motiontrack.evaluate.events import evaluate_events, match_times
from motiontrack.io.events import is_events_file, read_events, write_events
from motiontrack.types import Event

FPS = 10.0


def cross(t: float, direction: str = "in", line: str = "gate", track: int = 1) -> Event:
    return Event("line_cross", int(round(t * FPS)) + 1, t, track, 0.0, 0.0, line=line,
                 direction=direction)


def enter(t: float, zone: str = "plaza", track: int = 1) -> Event:
    return Event("zone_enter", int(round(t * FPS)) + 1, t, track, 0.0, 0.0, zone=zone)


def left(t: float, track: int = 2) -> Event:
    return Event("abandoned", int(round(t * FPS)) + 1, t, track, 0.0, 0.0, duration_s=5.0)


# ------------------------------------------------------------------------------------ matching
@pytest.mark.parametrize("gt, pred, tol, expected", [
    ([], [], 1.0, []),
    ([1.0], [], 1.0, []),
    ([], [1.0], 1.0, []),
    ([5.0], [6.0], 1.0, [(0, 0)]),          # |Δt| = 1.0: just inside (the bound counts)
    ([5.0], [6.01], 1.0, []),                # |Δt| = 1.01: just outside
    ([0.1], [1.1], 1.0, [(0, 0)]),           # 1.1 − 0.1 rounds to 1.0000000000000002: inside
    ([5.0], [4.5, 5.2], 1.0, [(0, 1)]),      # two candidates: the closer one
    ([5.0, 6.0], [5.9], 1.0, [(1, 0)]),      # one prediction, two gt: the closer gt
    # greedy nearest would pair gt 5.0 with 5.6 (|Δt| 0.6) and leave gt 6.5 unmatched (7.6 is
    # 1.1 away); the optimum matches both: 5.0–4.5 (0.5) and 6.5–5.6 (0.9)
    ([5.0, 6.5], [4.5, 5.6], 1.0, [(0, 0), (1, 1)]),
    # as many matches as possible before the smallest total: 1.0–1.9 (0.9) and 2.0–2.5 (0.5),
    # not 2.0–1.9 alone (0.1), which would leave both others unmatched
    ([1.0, 2.0], [1.9, 2.5], 1.0, [(0, 0), (1, 1)]),
    ([3.0], [3.0], 0.0, [(0, 0)]),            # zero tolerance: equal times only
])
def test_match_times(gt, pred, tol, expected):
    assert match_times(gt, pred, tol) == expected


def test_tie_counts_one_match_and_one_false_positive():
    # two predictions 0.5 s either side of one crossing: one matches, one is a false positive
    r = evaluate_events([cross(10.0)], [cross(9.5), cross(10.5)])
    s = r.total
    assert (s.gt, s.pred, s.tp, s.fp, s.fn) == (1, 2, 1, 1, 0)
    assert s.precision == 1 / 2 and s.recall == 1 / 1 and s.f1 == 2 * 1 / (2 * 1 + 1 + 0)
    assert s.count_error == 2 - 1 and s.mean_abs_dt_s == 0.5


def test_one_gt_claimed_by_two_predictions_matches_once():
    # both predictions are within 1 s of the single crossing at 4.0; the crossing at 9.0 has
    # none: TP 1, FP 1, FN 1
    r = evaluate_events([cross(4.0), cross(9.0)], [cross(3.8), cross(4.1)])
    s = r.total
    assert (s.tp, s.fp, s.fn) == (1, 1, 1)
    assert s.precision == 1 / 2 and s.recall == 1 / 2 and s.f1 == 2 * 1 / (2 * 1 + 1 + 1)
    assert s.count_error == 2 - 2
    assert s.mean_abs_dt_s == pytest.approx(0.1)  # the closer one, 4.1


def test_other_direction_line_or_zone_never_matches():
    gt = [cross(2.0, "in"), cross(5.0, "in", line="gate"), enter(7.0, "plaza")]
    pred = [cross(2.0, "out"), cross(5.0, "in", line="door"), enter(7.0, "kiosk")]
    r = evaluate_events(gt, pred)
    assert r.total.tp == 0 and r.total.fp == 3 and r.total.fn == 3
    # one group per type, line or zone and direction, in type order, then name, then direction
    assert list(r.groups) == [("line_cross", "door", "in"), ("line_cross", "gate", "in"),
                              ("line_cross", "gate", "out"), ("zone_enter", "kiosk", ""),
                              ("zone_enter", "plaza", "")]
    g = r.groups[("line_cross", "gate", "in")]
    assert (g.gt, g.pred, g.tp) == (2, 0, 0) and g.precision is None and g.recall == 0.0
    assert g.count_error == 0 - 2


def test_track_ids_do_not_matter():
    r = evaluate_events([cross(1.0, track=1)], [cross(1.2, track=99)])
    assert r.total.tp == 1


def test_scores_per_group_per_type_and_total():
    gt = [cross(1.0, "in"), cross(3.0, "in"), cross(4.0, "out"), enter(2.0), left(20.0)]
    pred = [cross(1.4, "in"), cross(4.5, "out"), cross(8.0, "out"), enter(2.0), enter(12.0)]
    r = evaluate_events(gt, pred, tolerance_s=0.5)
    grp = {k: (s.gt, s.pred, s.tp, s.fp, s.fn, s.count_error) for k, s in r.groups.items()}
    assert grp == {
        ("line_cross", "gate", "in"): (2, 1, 1, 0, 1, 1 - 2),     # 1.4 matches 1.0 (0.4 ≤ 0.5)
        ("line_cross", "gate", "out"): (1, 2, 1, 1, 0, 2 - 1),    # 4.5 matches 4.0 exactly at 0.5
        ("zone_enter", "plaza", ""): (1, 2, 1, 1, 0, 2 - 1),
        ("abandoned", "", ""): (1, 0, 0, 0, 1, 0 - 1),
    }
    t = r.by_type
    assert (t["line_cross"].gt, t["line_cross"].tp, t["line_cross"].count_error) == (3, 2, 3 - 3)
    s = r.total
    assert (s.gt, s.pred, s.tp, s.fp, s.fn) == (5, 5, 3, 2, 2)
    assert s.f1 == 2 * 3 / (2 * 3 + 2 + 2)
    assert s.mean_abs_dt_s == pytest.approx((0.4 + 0.5 + 0.0) / 3)
    out = r.to_json()
    assert out["groups"][0] == {"type": "line_cross", "line": "gate", "direction": "in",
                                "gt": 2, "pred": 1, "tp": 1, "fp": 0, "fn": 1, "precision": 1.0,
                                "recall": 0.5, "f1": round(2 / 3, 6), "count_error": -1,
                                "mean_abs_dt_s": 0.4}
    assert out["groups"][3]["type"] == "abandoned" and "zone" not in out["groups"][3]
    assert out["total"]["tp"] == 3 and out["tolerance_s"] == 0.5


def test_empty_inputs():
    r = evaluate_events([], [])
    assert r.groups == {}
    s = r.total
    assert (s.gt, s.pred, s.tp) == (0, 0, 0)
    assert s.precision is None and s.recall is None and s.f1 is None and s.count_error == 0
    only_gt = evaluate_events([enter(1.0)], []).total
    assert only_gt.recall == 0.0 and only_gt.precision is None and only_gt.f1 == 0.0


@pytest.mark.parametrize("tol", [-0.1, float("nan"), float("inf")])
def test_bad_tolerance(tol):
    with pytest.raises(ConfigError, match="tolerance"):
        evaluate_events([], [], tol)


# --------------------------------------------------------------------------------- events files
def test_events_file_round_trips(tmp_path):
    events = [cross(1.0), enter(2.5), left(9.0)]
    path = tmp_path / "events.jsonl"
    write_events(path, events, FPS, source="v.avi", scene="s.toml")
    assert is_events_file(path)
    got = read_events(path)
    assert got.header == {"schema": "motiontrack.events", "version": 1, "fps": FPS,
                          "source": "v.avi", "scene": "s.toml"}
    assert list(got.events) == events and got.fps == FPS


HEADER = '{"schema": "motiontrack.events", "version": 1, "fps": 25.0, "source": "", "scene": ""}'


@pytest.mark.parametrize("text, message", [
    ("", "is empty"),
    ("\n\n", "is empty"),
    ('{"type": "zone_enter"}\n', "not an events file"),
    ("1,1,10,10,20,40,1,-1,-1,-1\n", "not a JSON object"),
    (HEADER.replace('"version": 1', '"version": 2') + "\n", "schema version 2"),
    (HEADER.replace('"version": 1', '"version": "1"') + "\n", "version must be an integer"),
    (HEADER.replace('25.0', '0') + "\n", "fps must be a number > 0"),
    (HEADER + '\n{"type": "teleport", "frame": 1, "t": 0, "track": 1, "x": 0, "y": 0}\n',
     ":2: event type must be one of line_cross"),
    (HEADER + '\n\n{"type": "zone_enter", "frame": 1, "t": 0, "track": 1, "x": 0, "y": 0}\n',
     ":3: zone_enter event needs zone"),
    (HEADER + '\n{"type": "zone_enter", "frame": 1, "t": NaN, "track": 1, "x": 0, "y": 0, '
     '"zone": "a"}\n', ":2: not a JSON object (NaN is not a number JSON allows)"),
    (HEADER + "\n[1, 2]\n", ":2: an event must be a JSON object"),
])
def test_bad_events_files(tmp_path, text, message):
    path = tmp_path / "events.jsonl"
    path.write_text(text)
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        read_events(path)


def test_missing_events_file(tmp_path):
    with pytest.raises(InputError, match="events file"):
        read_events(tmp_path / "nope.jsonl")
    assert not is_events_file(tmp_path / "nope.jsonl")


# ------------------------------------------------------------------------------------- command
def test_evaluate_events_command(tmp_path, capsys):
    gt, pred = tmp_path / "gt.jsonl", tmp_path / "pred.jsonl"
    write_events(gt, [cross(1.0), cross(4.0, "out")], FPS)
    write_events(pred, [cross(1.5), cross(7.0, "out")], FPS)
    out = tmp_path / "m.json"
    assert main(["evaluate-events", "--gt", str(gt), "--pred", str(pred), "--json", str(out)]) == 0
    table = capsys.readouterr().out
    assert "line_cross gate in" in table and "TOTAL" in table
    m = json.loads(out.read_text())
    assert m["total"]["tp"] == 1 and m["total"]["fp"] == 1 and m["total"]["fn"] == 1
    assert m["tolerance_s"] == 1.0 and m["gt"] == str(gt)
    # a tighter tolerance loses the 0.5 s match
    assert main(["evaluate-events", "--gt", str(gt), "--pred", str(pred), "--tolerance-s",
                 "0.4", "--json", str(out), "--force"]) == 0
    assert json.loads(out.read_text())["total"]["tp"] == 0


def test_evaluate_events_command_errors(tmp_path, capsys):
    gt = tmp_path / "gt.jsonl"
    write_events(gt, [cross(1.0)], FPS)
    tracks = tmp_path / "tracks.txt"
    tracks.write_text("1,1,10,10,20,40,1,-1,-1,-1\n")
    cases = [
        (["--pred", str(tracks)], "is not an events file"),
        (["--pred", str(tmp_path / "none.jsonl")], "none.jsonl"),
        (["--pred", str(gt), "--tolerance-s", "-1"], "--tolerance-s must be"),
    ]
    for extra, message in cases:
        assert main(["evaluate-events", "--gt", str(gt), *extra]) == 2
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err and err.count("\n") == 1, err


def test_evaluate_events_analyses_tracks_files_with_a_scene(tmp_path, capsys):
    """A synthetic scene's ground-truth tracks, analysed on the fly with its scene file, give
    its ground-truth events (every event matched, at the same time)."""
    assert main(["synth-events", "crossing?seed=1", "-o", str(tmp_path)]) == 0
    out = tmp_path / "m.json"
    assert main(["evaluate-events", "--gt", str(tmp_path / "events.jsonl"), "--pred",
                 str(tmp_path / "gt.txt"), "--scene", str(tmp_path / "scene.toml"), "--fps",
                 "25", "--json", str(out)]) == 0
    m = json.loads(out.read_text())["total"]
    assert m["gt"] > 0 and m["tp"] == m["gt"] == m["pred"] and m["mean_abs_dt_s"] == 0.0
    # without a frame rate (none stated beside the file) a tracks file is refused
    assert main(["evaluate-events", "--gt", str(tmp_path / "events.jsonl"), "--pred",
                 str(tmp_path / "gt.txt"), "--scene", str(tmp_path / "scene.toml")]) == 2
    assert "--fps" in capsys.readouterr().err
