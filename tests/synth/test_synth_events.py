"""Synthetic scenes for scene analytics: the loiter and leftbag scenes, every scene's lines and
zones, and the exact ground-truth events their rules give."""

from __future__ import annotations

import logging
import math
import tomllib
from collections import Counter

import numpy as np
import pytest

from motiontrack.cli import main
from motiontrack.io.events import read_events
from motiontrack.io.mot import read_mot
from motiontrack.synth import SCENES, Bag, Person, SyntheticScene, make_scene
from motiontrack.synth.events import ground_truth_events
from motiontrack.synth.render import person_facing, person_position
from motiontrack.types import Annotations

SEEDS = range(10)


def _events(scene, kind, **fields):
    return [e for e in scene.ground_truth_events() if e.type == kind
            and all(getattr(e, k) == v for k, v in fields.items())]


def _gt_of(scene, oid):
    gt = scene.ground_truth()
    sel = gt.ids == oid
    return gt.frames[sel], gt.boxes[sel]


# ------------------------------------------------------------------------------ the new scenes
@pytest.mark.parametrize("name", ["loiter", "leftbag"])
def test_new_scenes_are_listed_and_render(name):
    assert name in SCENES
    s = make_scene(name, seed=1)
    img = s.frame(s.n_frames // 2)
    assert img.shape == (480, 640, 3) and img.dtype == np.uint8
    assert s.foreground_mask(s.n_frames // 2).any()
    assert not s.foreground_mask(5).any()  # empty background first, as in every scene
    assert s.ground_truth().frames.min() >= 16


def test_same_seed_same_new_scene():
    for name in ("loiter", "leftbag"):
        a, b = make_scene(name, seed=4), make_scene(name, seed=4)
        assert np.array_equal(a.frame(200), b.frame(200))
        assert [e.to_json() for e in a.ground_truth_events()] == \
            [e.to_json() for e in b.ground_truth_events()]


# ------------------------------------------------------------------------------ piecewise paths
def test_person_follows_turns_and_keeps_facing():
    # walks right at 2 px/frame, stands from index 10 to 20, then walks up-left at (-1, -0.5)
    p = Person(id=1, x0=100.0, y0=300.0, vx=2.0, vy=0.0, height=90.0, t0=0.0,
               turns=((10.0, 0.0, 0.0), (20.0, -1.0, -0.5)))
    assert person_position(p, 5)[:2] == (110.0, 300.0)     # 100 + 2·5
    assert person_position(p, 15)[:2] == (120.0, 300.0)    # stopped at 100 + 2·10
    assert person_position(p, 24)[:2] == (116.0, 298.0)    # 120 − 1·4, 300 − 0.5·4
    assert person_facing(p, 15) == 1.0   # standing: still facing right
    assert person_facing(p, 24) == -1.0  # walking left
    assert p.travelled(15) == 20.0 and p.travelled(24) == pytest.approx(20 + 4 * math.hypot(1, 0.5))


def test_standing_person_keeps_pose():
    p = Person(id=1, x0=100.0, y0=300.0, vx=2.0, vy=0.0, height=90.0, t0=0.0,
               turns=((10.0, 0.0, 0.0),))
    s = SyntheticScene("custom", 0, 320, 400, 25.0, 40, people=(p,), noise=0.0)
    assert np.array_equal(s.foreground_mask(12), s.foreground_mask(30))
    assert not np.array_equal(s.foreground_mask(4), s.foreground_mask(6))


@pytest.mark.parametrize("turns, message", [
    (((5.0, 1.0, 0.0), (5.0, 0.0, 0.0)), "turn times must increase"),
    (((-1.0, 1.0, 0.0),), "turn times must increase"),
    (((5.0, math.nan, 0.0),), "finite"),
])
def test_person_turns_validate(turns, message):
    with pytest.raises(ValueError, match=message):
        Person(id=1, x0=0.0, y0=300.0, vx=1.0, vy=0.0, height=90.0, turns=turns)


def test_bag_needs_an_owner_and_its_own_id():
    p = Person(id=1, x0=0.0, y0=300.0, vx=1.0, vy=0.0, height=90.0)
    with pytest.raises(ValueError, match="no owner"):
        SyntheticScene("c", 0, 320, 400, 25.0, 40, people=(p,), bags=(Bag(2, owner=7, t_drop=10),))
    with pytest.raises(ValueError, match="unique"):
        SyntheticScene("c", 0, 320, 400, 25.0, 40, people=(p,), bags=(Bag(1, owner=1, t_drop=10),))


# ------------------------------------------------------------------------------------ leftbag
@pytest.mark.parametrize("seed", SEEDS)
def test_leftbag_bag_splits_off_lies_still_and_the_owner_leaves(seed):
    s = make_scene("leftbag", seed=seed)
    (bag,), (owner,) = s.bags, s.people
    frames, boxes = _gt_of(s, bag.id)
    # the bag is an object of its own from the frame it rests on the ground, to the end
    assert frames[0] == bag.t_drop + 1 and frames[-1] == s.n_frames
    assert np.array_equal(frames, np.arange(frames[0], s.n_frames + 1))
    assert np.all(boxes == boxes[0])  # static, to the pixel
    # before, it is part of its owner: the owner's box holds the carried bag
    of, ob = _gt_of(s, owner.id)
    carried = s.ground_truth().at(bag.t_drop)  # frame number t_drop = index t_drop - 1
    assert list(carried.ids) == [owner.id]
    # the owner walks out of view long before the end
    assert of[-1] < s.n_frames - 25
    assert abs(ob[-1, 0] + ob[-1, 2] / 2 - 320) > 320  # last seen at a border
    # events: the bag is stationary 3 s after it lands and abandoned 4 s after its owner is
    # 1.5 of their heights away; nobody else is stationary or abandoned
    fps = s.fps
    (st,) = _events(s, "stationary_start")
    assert st.track == bag.id and st.frame == frames[0] + round(3.0 * fps)
    (ab,) = _events(s, "abandoned")
    assert ab.track == bag.id and ab.owner == owner.id
    cx, bottom = boxes[0, 0] + boxes[0, 2] / 2, boxes[0, 1] + boxes[0, 3]
    away = [f for f, b in zip(of, ob) if f >= frames[0]
            and math.hypot(b[0] + b[2] / 2 - cx, b[1] + b[3] - bottom) > 1.5 * b[3]]
    assert np.array_equal(away, np.arange(away[0], of[-1] + 1))  # and never comes back
    assert ab.frame == away[0] + round(4.0 * fps)
    assert ab.duration_s == pytest.approx((ab.frame - frames[0]) / fps)
    assert ab.x == cx and ab.y == bottom


def test_leftbag_describe_names_the_drop():
    d = make_scene("leftbag", seed=2).describe()
    assert d["bags"][0]["owner"] == 1 and d["bags"][0]["first_frame"] == d["bags"][0]["dropped_frame"]
    assert any("sets bag 2 down" in e["what"] for e in d["events"])
    assert [e["type"] for e in d["analytics_events"]].count("abandoned") == 1


# ------------------------------------------------------------------------------------- loiter
@pytest.mark.parametrize("seed", SEEDS)
def test_loiter_time_is_known(seed):
    s = make_scene("loiter", seed=seed)
    (zone,) = s.scene_file["zone"]
    (enter,) = _events(s, "zone_enter", zone="plaza")
    (loiter,) = _events(s, "loiter", zone="plaza")
    (leave,) = _events(s, "zone_exit", zone="plaza")
    # loiter exactly loiter_s after entering: 5 s · 25 fps = 125 frames
    assert loiter.frame - enter.frame == round(zone["loiter_s"] * s.fps) == 125
    assert loiter.dwell_s == 5.0
    # the stay lasts the lingering (7-9 s between the first and last point) and more
    assert leave.dwell_s == (leave.frame - enter.frame) / s.fps
    assert 9.0 <= leave.dwell_s <= 12.5  # docs/synthetic.md: 9.1-12.1 s on seeds 0-9
    # a lingering walk, never standing: nobody is stationary
    assert not _events(s, "stationary_start")
    person = s.people[0]
    assert len(person.turns) == 4 and all(math.hypot(vx, vy) >= 0.3 for _, vx, vy in person.turns)


# ------------------------------------------------------------------------------- line counts
@pytest.mark.parametrize("name", ["walker", "runner", "lighting"])
@pytest.mark.parametrize("seed", SEEDS)
def test_one_walker_crosses_the_gate_once_in_its_direction(name, seed):
    s = make_scene(name, seed=seed)
    (e,) = _events(s, "line_cross")
    # the gate is drawn bottom to top, so left to right is "in" (s < 0 to s > 0)
    assert e.line == "gate" and e.direction == ("in" if s.people[0].vx > 0 else "out")
    assert abs(e.x - s.scene_file["line"][0]["points"][0][0]) <= 5 + 8  # just past it


@pytest.mark.parametrize("seed", SEEDS)
def test_crossing_counts_one_each_way(seed):
    s = make_scene("crossing", seed=seed)
    crossings = _events(s, "line_cross")
    assert sorted(e.direction for e in crossings) == ["in", "out"]
    for e in crossings:
        p = s.people[e.track - 1]
        assert e.direction == ("in" if p.vx > 0 else "out")


@pytest.mark.parametrize("seed", SEEDS)
def test_crowd_crossings_follow_each_walker(seed):
    s = make_scene("crowd", seed=seed)
    per = Counter((e.track, e.direction) for e in _events(s, "line_cross"))
    assert per and all(n == 1 for n in per.values())
    for (tid, direction) in per:
        assert direction == ("in" if s.people[tid - 1].vx > 0 else "out")


@pytest.mark.parametrize("name", ["walker", "runner", "column", "crossing", "crowd", "lighting",
                                  "loiter"])
def test_no_abandoned_or_stationary_without_a_bag(name):
    for seed in (0, 1, 2):
        s = make_scene(name, seed=seed)
        kinds = {e.type for e in s.ground_truth_events()}
        assert not kinds & {"abandoned", "stationary_start", "stationary_end"}


# ------------------------------------------------------------------------------ the scene file
@pytest.mark.parametrize("name", SCENES)
def test_scene_file_toml_round_trips(name):
    s = make_scene(name, seed=3)
    assert tomllib.loads(s.scene_toml()) == s.scene_file
    d = s.describe()
    assert d["scene_file"] == s.scene_file
    assert d["analytics_events"] == [e.to_json() for e in s.ground_truth_events()]
    d["scene_file"]["line"].clear()  # the description is a copy: the scene keeps its lines
    assert s.scene_file["line"] and tomllib.loads(s.scene_toml()) == s.scene_file


def test_scene_file_scales_with_the_frame():
    small, big = make_scene("walker", seed=0, width=320, height=240), make_scene("walker", seed=0)
    assert small.scene_file["line"][0]["points"][0][0] == 160.25
    assert big.scene_file["line"][0]["points"][0][0] == 320.25
    assert len(_events(small, "line_cross")) == 1


def test_hand_built_events_follow_the_rules():
    """One object, 10 fps, walking right 4 px/frame along y = 100 from x = 0 (frames 1..30)."""
    f = np.arange(1, 31)
    x = 4.0 * (f - 1)                      # anchor x = box x + w / 2 with w = 10
    gt = Annotations.from_columns(frames=f, ids=np.ones(30, int),
                                  boxes=np.column_stack([x - 5, np.full(30, 80.0),
                                                         np.full(30, 10.0), np.full(30, 20.0)]))
    scene_file = {
        "hysteresis_px": 2.0,
        # bottom to top at x = 50.25: walking right is "in"
        "line": [{"name": "l", "points": [[50.25, 200.0], [50.25, 0.0]]}],
        "zone": [{"name": "z", "polygon": [[20.25, 0], [80.25, 0], [80.25, 200], [20.25, 200]],
                  "loiter_s": 1.0}],
    }
    ev = ground_truth_events(scene_file, gt, fps=10.0)
    got = [(e.type, e.frame, e.x) for e in ev]
    assert got == [
        # frame 7: x = 24 is 3.75 px inside (> 2 hysteresis)
        ("zone_enter", 7, 24.0),
        # frame 15: x = 56, 5.75 px past the line (frame 14, x = 52, is only 1.75 px past)
        ("line_cross", 15, 56.0),
        # frame 7 + 1 s · 10 fps
        ("loiter", 17, 64.0),
        # frame 22: x = 84 is 3.75 px outside (frame 21, x = 80, is inside)
        ("zone_exit", 22, 84.0),
    ]
    assert ev[1].direction == "in" and ev[3].dwell_s == (22 - 7) / 10.0 and ev[2].t == 1.6


# -------------------------------------------------------------------- against the analytics
@pytest.mark.parametrize("name", SCENES)
def test_analytics_on_the_ground_truth_finds_the_ground_truth_events(name, caplog):
    """The scene analytics run over every ground-truth row give exactly the synthetic events
    (``abandoned`` aside: the analytics find it from tracks splitting, not from owners)."""
    from motiontrack.analytics import Analytics
    from motiontrack.analytics.scene import parse_scene

    def as_set(events):   # (the ground-truth events name no class)
        return {tuple(sorted((k, v) for k, v in e.to_json().items() if k != "label"))
                for e in events if e.type != "abandoned"}

    caplog.set_level(logging.ERROR)
    for seed in (0, 1):
        s = make_scene(name, seed=seed)
        an = Analytics(parse_scene(tomllib.loads(s.scene_toml())), s.fps)
        gt, found = s.ground_truth(), []
        by = gt.by_frame()
        classes = s.object_classes()   # the rules with classes see each object's own
        for f in range(1, s.n_frames + 1):
            rows = by.get(f, np.zeros(0, dtype=np.int64))
            labels = [classes[i] for i in gt.ids[rows].tolist()]
            found += an.step(f, gt.ids[rows], gt.boxes[rows], labels=labels).events
        assert as_set(found) == as_set(s.ground_truth_events()), (name, seed)


# ------------------------------------------------------------------------------- synth-events
def test_synth_events_command_writes_scene_gt_and_events(tmp_path, capsys):
    out = tmp_path / "lb"
    assert main(["synth-events", "leftbag?seed=3", "-o", str(out)]) == 0
    assert "1 abandoned" in capsys.readouterr().out
    s = make_scene("leftbag", seed=3)
    ev = read_events(out / "events.jsonl")
    assert ev.header["fps"] == 25.0 and ev.header["source"] == s.spec
    assert list(ev.events) == s.ground_truth_events()
    assert tomllib.loads((out / "scene.toml").read_text()) == s.scene_file
    gt = read_mot(out / "gt.txt")
    assert len(gt) == len(s.ground_truth()) and set(gt.ids.tolist()) == {1, 2}
    # a second run refuses to replace them without --force
    assert main(["synth-events", "synth:leftbag?seed=3", "-o", str(out)]) != 0
    assert main(["synth-events", "synth:leftbag?seed=3", "-o", str(out), "--force"]) == 0


def test_synth_events_command_refuses_unknown_scene(tmp_path, capsys):
    assert main(["synth-events", "nosuch", "-o", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert "unknown synthetic scene 'nosuch'" in err and "Traceback" not in err
