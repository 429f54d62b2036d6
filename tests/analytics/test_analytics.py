"""Scene analytics: hand-built per-frame scenarios with the expected events written out."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.analytics import Analytics, parse_scene
from motiontrack.analytics.geometry import (points_in_polygon, polygon_is_simple,
                                            segments_intersect, side)
from motiontrack.types import Box, Discontinuity, Track, TrackState

FPS = 10.0  # t = (frame - 1) / 10

#: a horizontal line from A = (0, 100) to B = (200, 100): s(p) = 200 (py - 100), so s > 0 below
GATE = {"name": "gate", "points": [[0, 100], [200, 100]]}
#: a U-shaped (concave) zone: the notch x in (40, 60), y in (0, 60) is outside
U_ZONE = {"name": "u", "polygon": [[0, 0], [40, 0], [40, 60], [60, 60], [60, 0], [100, 0],
                                   [100, 100], [0, 100]]}


def foot(x: float, y: float, w: float = 10.0, h: float = 20.0) -> list[float]:
    """The box whose bottom centre (the default anchor) is (x, y)."""
    return [x - w / 2.0, y - h, w, h]


def run(scene: dict, frames: dict[int, dict[int, tuple[float, float]]], last: int | None = None,
        fps: float = FPS) -> list[dict]:
    """Events of ``frames`` (frame → {track id: anchor}) as JSON objects; every frame from 1 to
    ``last`` is a step (those not listed have no tracks)."""
    an = Analytics(parse_scene(scene), fps)
    out = []
    for f in range(1, (last or max(frames)) + 1):
        tracks = frames.get(f, {})
        fr = an.step(f, list(tracks), [foot(*p) for p in tracks.values()])
        out += [e.to_json() for e in fr.events]
    return out


def kinds(events: list[dict], *keys: str) -> list[tuple]:
    return [tuple(e.get(k) for k in ("type", "frame", "track", *keys)) for e in events]


# ------------------------------------------------------------------------------------ geometry
def test_side_sign_follows_the_documented_formula():
    # A=(0,0), B=(10,0): s = 10 * py; below the line on screen (y down) is positive
    assert side([[5, 3], [5, -3], [50, 0]], (0, 0), (10, 0)).tolist() == [30.0, -30.0, 0.0]


def test_segments_meet_only_through_the_segment_not_its_extension():
    hit = segments_intersect([[5, -1], [15, -1], [0, -1]], [[5, 1], [15, 1], [0, 0]], (0, 0), (10, 0))
    assert hit.tolist() == [True, False, True]  # through, beside (extension), touching A


def test_point_in_concave_polygon_and_simple_polygon_check():
    poly = U_ZONE["polygon"]
    inside = points_in_polygon([[20, 20], [50, 20], [80, 20], [50, 80], [150, 50]], poly)
    assert inside.tolist() == [True, False, True, True, False]
    assert polygon_is_simple(poly)
    assert not polygon_is_simple([[0, 0], [10, 10], [10, 0], [0, 10]])  # a bow tie
    assert points_in_polygon(np.zeros((0, 2)), poly).shape == (0,)


# -------------------------------------------------------------------------------------- lines
def test_line_crossing_both_directions_with_time_from_fps():
    frames = {
        1: {1: (100, 80), 2: (150, 130)},  # 1 above (s<0), 2 below (s>0): sides confirmed
        2: {1: (100, 95), 2: (150, 110)},  # both inside the 5 px band: nothing
        3: {1: (100, 106), 2: (150, 94)},  # both 6 px past the line: 1 goes in, 2 goes out
        4: {1: (100, 130), 2: (150, 70)},  # further on: nothing new
    }
    ev = run({"line": [GATE]}, frames)
    assert kinds(ev, "line", "direction") == [("line_cross", 3, 1, "gate", "in"),
                                               ("line_cross", 3, 2, "gate", "out")]
    assert ev[0]["t"] == pytest.approx(0.2) and (ev[0]["x"], ev[0]["y"]) == (100.0, 106.0)


def test_jitter_on_the_line_is_counted_once():
    ys = [80, 98, 103, 97, 104, 96, 102, 99, 108, 101, 130]
    # frames 1..11: above; then in the band (|d| <= 5) going back and forth across the line;
    # frame 9 (y=108) is the first confirmed position below → one "in"; 10 (y=101) is in the
    # band again (no change); 11 goes on below
    ev = run({"line": [GATE]}, {f: {7: (100, y)} for f, y in enumerate(ys, 1)})
    assert kinds(ev, "direction") == [("line_cross", 9, 7, "in")]


def test_jitter_larger_than_hysteresis_counts_each_real_crossing():
    ys = [80, 110, 90, 110]  # each step crosses the line by 10 px: in, out, in
    ev = run({"line": [GATE]}, {f: {1: (100, y)} for f, y in enumerate(ys, 1)})
    assert [e["direction"] for e in ev] == ["in", "out", "in"]


def test_passing_beside_the_segment_is_no_crossing():
    # crosses y = 100 at x = 300, beyond B = (200, 100)
    ev = run({"line": [GATE]}, {1: {1: (300, 80)}, 2: {1: (300, 120)}})
    assert ev == []


def test_a_track_born_on_the_line_or_past_it_does_not_count():
    frames = {
        1: {1: (100, 101)},  # first seen in the band: side unknown
        2: {1: (100, 120)},  # side confirmed below: nothing (it never was above)
    }
    assert run({"line": [GATE]}, frames) == []


def test_a_fast_track_jumping_over_the_band_counts():
    ev = run({"line": [GATE]}, {1: {1: (100, 50)}, 2: {1: (100, 150)}})
    assert kinds(ev, "direction") == [("line_cross", 2, 1, "in")]


def test_line_reversed_swaps_directions():
    rev = {"name": "gate", "points": [[200, 100], [0, 100]]}  # B→A: s > 0 above
    ev = run({"line": [rev]}, {1: {1: (100, 80)}, 2: {1: (100, 120)}})
    assert [e["direction"] for e in ev] == ["out"]


# -------------------------------------------------------------------------------------- zones
def test_zone_enter_exit_with_dwell_in_a_concave_zone():
    frames = {
        1: {1: (50, 20)},   # in the U's notch: outside
        2: {1: (50, 80)},   # below the notch, inside (20 px from the nearest edge): enter
        3: {1: (80, 50)},   # inside the right arm
        4: {1: (50, 30)},   # back in the notch, 10 px from its edges: exit, dwell 0.2 s
    }
    ev = run({"zone": [U_ZONE]}, frames)
    assert kinds(ev, "zone", "dwell_s") == [("zone_enter", 2, 1, "u", None),
                                             ("zone_exit", 4, 1, "u", 0.2)]


def test_zone_edge_jitter_is_one_stay():
    # the right edge x = 100: inside beyond 95, outside beyond 105
    xs = [90, 99, 101, 98, 102, 110, 103, 97, 90]
    # frame 1 inside (enter), 2-5 in the band, 6 outside (exit, dwell 0.5 s), 7-8 band, 9 inside
    ev = run({"zone": [U_ZONE]}, {f: {3: (x, 50)} for f, x in enumerate(xs, 1)})
    assert kinds(ev, "dwell_s") == [("zone_enter", 1, 3, None), ("zone_exit", 6, 3, 0.5),
                                    ("zone_enter", 9, 3, None)]


def test_loiter_once_per_stay():
    zone = {**U_ZONE, "loiter_s": 0.3}
    frames = {f: {1: (20, 50)} for f in range(1, 7)}   # inside from frame 1 (t = 0)
    frames.update({7: {1: (150, 50)}, 8: {1: (20, 50)}})  # leaves at 7, back at 8
    frames.update({f: {1: (20, 50)} for f in range(9, 13)})
    ev = run({"zone": [zone]}, frames)
    # loiter when frame - enter >= 3 frames: frame 4 (first stay), frame 11 (second, from 8)
    assert kinds(ev, "dwell_s") == [
        ("zone_enter", 1, 1, None), ("loiter", 4, 1, 0.3), ("zone_exit", 7, 1, 0.6),
        ("zone_enter", 8, 1, None), ("loiter", 11, 1, 0.3)]


def test_a_track_that_disappears_inside_a_zone_exits_when_forgotten():
    scene = {"forget_s": 0.5, "zone": [U_ZONE]}
    frames = {1: {4: (20, 50)}, 2: {4: (22, 50)}, 3: {4: (24, 50)}}
    # last seen at frame 3; unseen for more than 5 frames at frame 9: exit there, at its last
    # position, dwell up to its last sighting (frames 1..3 = 0.2 s)
    ev = run(scene, frames, last=12)
    assert kinds(ev, "dwell_s") == [("zone_enter", 1, 4, None), ("zone_exit", 9, 4, 0.2)]
    assert (ev[1]["x"], ev[1]["y"]) == (24.0, 50.0)


def test_a_reused_track_id_is_a_new_track_after_it_was_forgotten():
    scene = {"forget_s": 0.2, "zone": [U_ZONE], "line": [GATE]}
    frames = {
        1: {5: (20, 50)},    # enters u
        2: {5: (20, 50)},
        # frames 3-5: unseen; forgotten at frame 5 (3 frames > 2): exit u
        8: {5: (150, 130)},  # the id again, far away below the gate: a new track, no crossing
        9: {5: (150, 80)},   # crosses the gate upwards: out
    }
    ev = run(scene, frames)
    assert kinds(ev) == [("zone_enter", 1, 5), ("zone_exit", 5, 5), ("line_cross", 9, 5)]
    assert ev[2]["direction"] == "out"


def test_a_short_gap_keeps_the_track_and_its_path():
    frames = {1: {1: (100, 80)}, 2: {}, 3: {}, 4: {1: (100, 120)}}  # unseen 2 frames < 2 s
    ev = run({"line": [GATE]}, frames)
    assert kinds(ev, "direction") == [("line_cross", 4, 1, "in")]


def test_no_tracks_and_no_rules_give_no_events():
    assert run({"line": [GATE], "zone": [U_ZONE]}, {1: {}, 2: {}}) == []
    an = Analytics(parse_scene({}), FPS)
    assert an.step(1, [1], [foot(5, 5)]).events == ()
    fr = Analytics(parse_scene({"line": [GATE], "zone": [U_ZONE]}), FPS).step(1, [], np.zeros((0, 4)))
    assert fr.events == () and fr.line_counts == {"gate": (0, 0)} and fr.occupancy == {"u": 0}


def test_occupancy_counts_and_summary_follow_the_events():
    scene = {"line": [GATE], "zone": [U_ZONE]}
    an = Analytics(parse_scene(scene), FPS)
    an.step(1, [1, 2], [foot(20, 50), foot(150, 80)])    # 1 in u; 2 above the gate
    fr = an.step(2, [1, 2], [foot(80, 50), foot(150, 120)])  # 2 crosses in
    assert fr.occupancy == {"u": 1} and fr.line_counts == {"gate": (1, 0)}
    fr = an.step(3, [1], [foot(150, 50)])                 # 1 leaves u
    assert fr.occupancy == {"u": 0}
    s = an.summary()
    assert s["lines"] == {"gate": {"in": 1, "out": 0}}
    assert s["zones"]["u"] == {"enters": 1, "exits": 1, "inside_at_end": 0, "peak": 1,
                               "mean_occupancy": round(2 / 3, 4), "mean_dwell_s": 0.2}
    assert s["events"]["line_cross"] == 1 and s["events"]["abandoned"] == 0


def test_update_takes_tracks_like_the_pipeline_reports():
    an = Analytics(parse_scene({"line": [GATE]}), FPS)
    t = lambda y: Track(3, Box(*foot(100, y)), TrackState.CONFIRMED)  # noqa: E731
    assert an.update(1, [t(80)]) == []
    assert [e.direction for e in an.update(2, [t(120)])] == ["in"]


def test_frames_must_increase():
    an = Analytics(parse_scene({}), FPS)
    an.step(2, [], np.zeros((0, 4)))
    with pytest.raises(ValueError, match="increasing"):
        an.step(2, [], np.zeros((0, 4)))


def test_a_discontinuity_drops_every_track_without_events_and_keeps_the_totals():
    scene = {"line": [GATE], "zone": [U_ZONE], "stationary": {"after_s": 0.2, "radius_px": 3}}
    an = Analytics(parse_scene(scene), FPS)
    an.step(1, [1, 2], [foot(20, 50), foot(150, 80)])      # 1 in u; 2 above the gate
    an.step(2, [1, 2], [foot(20, 50), foot(150, 120)])     # 2 crosses in
    fr = an.step(3, [1], [foot(20, 50)])                   # 1 still for 2 frames: stationary
    assert [e.type for e in fr.events] == ["stationary_start"] and fr.occupancy == {"u": 1}
    # frame 4 comes after a loop: track 1 (the same id, now at the gate's far end) is a new
    # track; its stay, its zone membership and track 2 are gone without stationary_end,
    # zone_exit or a crossing, and the zone is empty; the gate keeps its total
    fr = an.step(4, [1], [foot(150, 80)], discontinuity=Discontinuity("loop"))
    assert fr.events == () and fr.discontinuity == Discontinuity("loop")
    assert fr.occupancy == {"u": 0} and fr.line_counts == {"gate": (1, 0)}
    fr = an.step(5, [1], [foot(20, 50)])                   # back in u: a new entry
    assert [e.type for e in fr.events] == ["zone_enter"] and fr.discontinuity is None
    s = an.summary()
    assert s["discontinuities"] == {"loop": 1} and s["lines"] == {"gate": {"in": 1, "out": 0}}
    assert s["zones"]["u"]["enters"] == 2 and s["zones"]["u"]["exits"] == 0
    assert s["stationary_at_end"] == 0


# ------------------------------------------------------------------------ stationary and speed
#: release 1.5: 4.5 px once stationary; a stay ends at the first position out of reach
STAY = {"stationary": {"after_s": 0.3, "radius_px": 3, "leave_s": 0}}


def test_stationary_start_and_end():
    # frames 1-10 still at x = 50: the stay lasts 3 frames at frame 4 (stationary_start); from
    # frame 11 a walk at 2 px a frame (2 heights a second): the smoothed position lags the
    # box, is within 4.5 px of the stay's centre up to frame 12 and beyond it at frame 13
    xs = [50] * 10 + [50 + 2 * k for k in range(1, 15)]
    ev = run(STAY, {f: {2: (x, 50)} for f, x in enumerate(xs, 1)})
    assert kinds(ev, "duration_s") == [("stationary_start", 4, 2, None),
                                       ("stationary_end", 13, 2, 1.1)]


def test_a_box_that_jumps_for_one_frame_does_not_end_a_stop():
    # frame 11: the box 8 px off (8 sigma of its 1 px jitter: a neighbour joined the blob);
    # the raw anchor would be 8 px from the stay's centre, the smoothed one skips it
    xs = [50] * 10 + [58] + [50] * 5
    ev = run(STAY, {f: {2: (x, 50)} for f, x in enumerate(xs, 1)})
    assert kinds(ev) == [("stationary_start", 4, 2)]


def test_a_stop_ends_only_beyond_its_release():
    # shifting the weight 4 px (1.33 radii) away stays one stop; a step 7 px away (2.33 radii)
    # ends it at frame 16 and starts a new stay there, stationary again 3 frames later
    shift = [50] * 10 + [51, 52, 53, 54] + [54] * 10
    assert kinds(run(STAY, {f: {2: (x, 50)} for f, x in enumerate(shift, 1)})) == [
        ("stationary_start", 4, 2)]
    step = [50] * 10 + [51, 52, 53, 54, 55, 56, 57] + [57] * 10
    assert kinds(run(STAY, {f: {2: (x, 50)} for f, x in enumerate(step, 1)}), "duration_s") == [
        ("stationary_start", 4, 2, None), ("stationary_end", 16, 2, 1.4),
        ("stationary_start", 19, 2, None)]


def test_a_passer_by_who_hides_a_standing_person_for_a_moment_ends_nothing():
    # frames 11-15 the box is 10 px off (merged with someone walking past), then back: with
    # leave_s = 1 s (10 frames) nothing ends; with 0.3 s the stop ends at frame 14 (3 frames
    # out) and a new one starts when the box is back
    xs = [50] * 10 + [60] * 5 + [50] * 15
    frames = {f: {2: (x, 50)} for f, x in enumerate(xs, 1)}
    patient = {"stationary": {"after_s": 0.3, "radius_px": 3, "leave_s": 1.0}}
    assert kinds(run(patient, frames)) == [("stationary_start", 4, 2)]
    hasty = {"stationary": {"after_s": 0.3, "radius_px": 3, "leave_s": 0.3}}
    assert [k for k, *_ in kinds(run(hasty, frames))] == [
        "stationary_start", "stationary_end", "stationary_start"]


def _jittered_run(fast: int) -> list[float]:
    """A walk at 5 px a frame (50 px/s), ``fast`` px a frame from frame 21 to 40, 5 px again
    after; the box jumps 3 px ahead and back every other frame."""
    xs, x = [], 0.0
    for f in range(1, 61):
        x += fast if 20 < f <= 40 else 5
        xs.append(x + (3 if f % 2 else -3))
    return xs


def test_box_jitter_raises_no_speeding():
    # 50 px/s with +-3 px of jitter: from one frame to the next the raw anchors read up to
    # 110 px/s, above the 100 px/s limit; the smoothed speed stays near 50
    xs = _jittered_run(fast=5)
    assert run({"speed": {"limit_px_s": 100, "window_s": 0.5}},
               {f: {1: (x, 50)} for f, x in enumerate(xs, 1)}) == []
    assert max(abs(b - a) for a, b in zip(xs, xs[1:])) * FPS == 110


def test_speeding_once_per_episode_after_min_s():
    # 200 px/s from frame 21 to 40; the filter follows the change of pace, the 0.5 s window
    # reads it once it lies past the change, and the speed is over the limit by two standard
    # deviations for min_s = 1 s at frame 36: one event, none while it stays fast
    xs = _jittered_run(fast=20)
    ev = run({"speed": {"limit_px_s": 100, "window_s": 0.5}},
             {f: {1: (x, 50)} for f, x in enumerate(xs, 1)})
    assert kinds(ev) == [("speeding", 36, 1)] and ev[0]["speed_px_s"] == pytest.approx(200, abs=5)
    # min_s = 0: as soon as the lower bound passes the limit, ten frames earlier
    ev = run({"speed": {"limit_px_s": 100, "window_s": 0.5, "min_s": 0}},
             {f: {1: (x, 50)} for f, x in enumerate(xs, 1)})
    assert kinds(ev) == [("speeding", 26, 1)]


# ---------------------------------------------------------------------------------- the scene
@pytest.mark.parametrize(
    "scene, message",
    [
        ({"colour": 1}, r"unknown scene key\(s\) colour; valid keys: anchor, hysteresis_px"),
        ({"anchor": "head"}, "anchor must be one of bottom_center, center, got 'head'"),
        ({"line": [{"name": "a", "points": [[0, 0]]}]}, r"line\[1\].points must be two \[x, y\] points"),
        ({"line": [GATE, {"name": "b", "points": [[0, 0], [0, 0.5]]}]}, r"line\[2\].points: the two"),
        ({"line": [GATE, GATE]}, r"line\[2\].name 'gate' is used twice"),
        ({"line": [{"points": [[0, 0], [5, 5]]}]}, r"line\[1\].name is required"),
        ({"line": [{"name": "a", "points": [[0, 0], [5, "x"]]}]}, r"line\[1\].points\[2\]\[2\] must be a number, got 'x'"),
        ({"line": [{"name": "a", "points": [[0, 0], [9, 9]], "world": [[0, 0], [1, 1]]}]},
         r"line\[1\] needs exactly one of points and world"),
        ({"line": [{"name": "a", "world": [[0, 0], [1, 1]]}]}, r"line\[1\].world is in metres and needs a camera"),
        ({"line": {"name": "a"}}, r"line must be an array of tables"),
        ({"zone": [{"name": "z", "polygon": [[0, 0], [5, 5]]}]}, r"zone\[1\].polygon must have at least 3"),
        ({"zone": [{"name": "z", "polygon": [[0, 0], [10, 10], [10, 0], [0, 10]]}]}, "simple polygon"),
        ({"zone": [{"name": "z", "polygon": [[0, 0], [5, 5], [10, 10]]}]}, "encloses no area"),
        ({"zone": [{**U_ZONE, "loiter_s": 0}]}, r"zone\[1\].loiter_s must be in \(0.0, 10000000\], got 0.0"),
        ({"zone": [{**U_ZONE, "dwell": 3}]}, r"unknown scene key\(s\) zone\[1\].dwell; valid keys in zone\[1\]: classes, loiter_s, name"),
        ({"stationary": {"after_s": 3}}, "stationary needs exactly one of radius_px and radius_m"),
        ({"stationary": {"radius_px": 3}}, "stationary.after_s is required"),
        ({"stationary": {"after_s": 3, "radius_m": 1}}, "stationary.radius_m is in metres"),
        ({"speed": {"limit_mps": 3}}, "speed.limit_mps is in metres and needs a camera"),
        ({"speed": {"limit_px_s": True}}, "speed.limit_px_s must be a number, got True"),
        ({"abandoned": {"after_s": 5}}, "abandoned needs exactly one of distance_m and distance_heights"),
        ({"hysteresis_px": -1}, r"hysteresis_px must be in \[0.0, 10000000\], got -1.0"),
        ({"forget_s": float("inf")}, "forget_s must be a finite number"),
        ({"line": [{"name": " ", "points": [[0, 0], [9, 9]]}]}, r"line\[1\].name must be a non-empty string, got ' '"),
        ({"line": [{"name": "a", "points": [[0, 0, 1], [9, 9]]}]}, r"line\[1\].points\[1\] must be \[x, y\]: an array of 2 numbers"),
        ({"zone": [{**U_ZONE, "polygon": [[0, 0], [1e9, 0], [0, 5]]}]}, r"zone\[1\].polygon\[2\]\[1\] must be in \[-10000000, 10000000\], got 1000000000.0"),
    ],
)
def test_bad_scenes_are_one_line_errors_naming_the_key(scene, message):
    from motiontrack.errors import ConfigError

    with pytest.raises(ConfigError, match=message) as err:
        parse_scene(scene)
    assert "\n" not in str(err.value)


class _ShiftCamera:
    """A stand-in ground plane: 1 m = 10 px, world origin at pixel (100, 200)."""

    def world_to_image(self, pts):
        pts = np.asarray(pts, dtype=float)
        return np.column_stack([100 + 10 * pts[:, 0], 200 + 10 * pts[:, 1]])

    def image_to_world(self, px):
        px = np.asarray(px, dtype=float).reshape(-1, 2)
        return np.column_stack([(px[:, 0] - 100) / 10, (px[:, 1] - 200) / 10])


def test_world_geometry_and_metre_rules_go_through_the_camera():
    cam = _ShiftCamera()
    scene = parse_scene({"line": [{"name": "g", "world": [[-10, -10], [10, -10]]}],
                         "speed": {"limit_mps": 3.0, "window_s": 0.2, "min_s": 0.2}},
                        camera=cam)
    assert scene.lines[0].a == (0.0, 100.0) and scene.lines[0].b == (200.0, 100.0)
    an = Analytics(scene, FPS, camera=cam)
    ev = []
    for f, y in enumerate([80, 95, 110, 125, 140, 155, 170, 185, 200], 1):
        ev += an.step(f, [1], [foot(100, y)]).events       # 15 px = 1.5 m a frame = 15 m/s
    # the line y = 100 px is crossed at frame 3 (y = 110, 10 px past it); the speed, on the
    # ground through the camera, is over 3 m/s by two deviations from frame 2 (the first window
    # spanning half its length) and speeding min_s = 0.2 s later, at frame 4
    assert [(e.type, e.frame) for e in ev] == [("line_cross", 3), ("speeding", 4)]
    assert (ev[0].X, ev[0].Y) == (0.0, -9.0) and ev[1].speed_mps == pytest.approx(15.0, abs=0.5)


def test_abandoned_without_static_foreground_yields_no_events_and_says_why(caplog):
    # abandoned objects come from the video (tests/analytics/test_abandoned.py); tracks alone have none
    scene = parse_scene({"abandoned": {"after_s": 5, "distance_heights": 2}})
    an = Analytics(scene, FPS)
    with caplog.at_level("WARNING"):
        assert an.step(1, [1], [(0, 0, 10, 10)]).events == ()
    assert "abandoned" in caplog.text and an.wants_static
