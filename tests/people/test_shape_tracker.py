"""Active shape tracker: normal search, fitting a synthetic walker, coasting, the people stage."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.people import PeopleConfig, PeopleStage
from motiontrack.people.shape_model import load_default_model
from motiontrack.people.shape_tracker import (
    FittedShape,
    ShapeTracker,
    ShapeTrackerParams,
    difference_gradients,
    edge_image,
    search_normals,
)
from motiontrack.tracking.association import iou_matrix
from motiontrack.types import Box, Track, TrackState

from helpers import tracks_of


def _track(tid: int, box, tsu: int = 0) -> Track:
    return Track(id=tid, box=Box(*map(float, box)), state=TrackState.CONFIRMED, time_since_update=tsu)


@pytest.mark.parametrize("radius", [10.0, 20.0])
def test_normal_search_finds_the_disc_boundary(radius):
    import cv2

    img = np.zeros((80, 80), np.uint8)
    cv2.circle(img, (40, 40), int(radius), 200, -1)
    bg = np.zeros_like(img)
    theta = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    nrm = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    start = 40 + (radius - 4) * nrm  # 4 px inside the boundary
    for edges in (edge_image(img, bg), difference_gradients(img, bg)):
        off, strength = search_normals(edges, start, nrm, half=8, threshold=5)
        assert (strength > 0).all()
        assert off == pytest.approx(np.full(16, 4.0), abs=1.5)


def test_oriented_search_ignores_edges_of_the_wrong_polarity():
    # A bright bar outside the outline: its near edge rises going outwards (wrong polarity).
    img = np.zeros((40, 40), np.uint8)
    img[:, 25:30] = 200
    gx, gy = difference_gradients(img, np.zeros_like(img))
    pts, nrm = np.array([[15.0, 20.0]]), np.array([[1.0, 0.0]])
    off, strength = search_normals((gx, gy), pts, nrm, half=16, threshold=5)
    assert off[0] == pytest.approx(14.5, abs=1.0)  # the far edge (drop), not the near one at +9.5
    assert strength[0] > 0


def test_empty_inputs():
    off, strength = search_normals(np.zeros((5, 5)), np.zeros((0, 2)), np.zeros((0, 2)), 3, 1)
    assert off.shape == strength.shape == (0,)
    st = ShapeTracker(load_default_model())
    assert st.update(np.zeros((48, 64, 3), np.uint8), np.zeros((24, 32, 3), np.uint8), [], []) == []


@pytest.fixture(scope="module")
def walker():
    from motiontrack.synth import make_scene

    scene = make_scene("walker", seed=1, noise=2.0)
    gt = scene.ground_truth()
    first = int(gt.frames[np.argmax((gt.boxes[:, 0] > 40) & (gt.visibility > 0.99))]) - 1
    return scene, gt, first


def test_tracker_follows_a_synthetic_walker(walker):
    scene, gt, first = walker
    bg = scene.background
    st = ShapeTracker(load_default_model())
    ious = []
    for i in range(first, first + 30):
        # the region tracker reports the track every frame; it only initialises the shape (a
        # shape that keeps finding edges is never re-initialised: coasting stays 0)
        out = st.update(scene.frame(i), bg, [], [_track(7, gt.at(i + 1).boxes[0])])
        assert len(out) == 1
        tid, outline, box = out[0]  # unpacks as (track_id, outline (K, 2), box)
        assert tid == 7 and outline.shape == (48, 2) and isinstance(out[0], FittedShape)
        assert out[0].coasting == 0 and out[0].support > 0.8
        ious.append(iou_matrix(box.as_array()[None], gt.at(i + 1).boxes)[0, 0])
    # measured: mean IoU ~0.85 (the outline misses the tips of swinging limbs)
    assert np.mean(ious) > 0.7
    assert min(ious) > 0.5


def test_tracker_coasts_when_the_person_vanishes_and_then_drops_it(walker):
    scene, gt, first = walker
    bg = scene.background
    st = ShapeTracker(load_default_model(), ShapeTrackerParams(max_coast=5))
    tracks = [_track(3, gt.at(first + 1).boxes[0])]
    for i in range(first, first + 12):
        out = st.update(scene.frame(i), bg, [], tracks)
        tracks = [_track(3, gt.at(i + 2).boxes[0])]
    x_before = out[0].box.x
    vx = out[0].box.x - st.update(scene.frame(first + 12), bg, [], tracks)[0].box.x
    # the person vanishes (frame == background): no edges; the outline moves on at its velocity
    coasting = [st.update(bg, bg, [], [_track(3, [0, 0, 1, 1], tsu=1)]) for _ in range(5)]
    assert all(len(o) == 1 and o[0].support == 0.0 for o in coasting)
    assert [o[0].coasting for o in coasting] == [1, 2, 3, 4, 5]
    assert abs(coasting[-1][0].box.x - x_before) > 2 * abs(vx) > 0
    assert st.update(bg, bg, [], []) == []  # coasted longer than max_coast: dropped


def test_people_stage_end_to_end_on_the_walker(walker):
    scene, gt, first = walker
    bg = scene.background
    stage = PeopleStage(PeopleConfig(enabled=True))
    mask = scene.foreground_mask(first)
    from motiontrack.motion.regions import components

    regions = components(mask)
    tracks = [_track(1, gt.at(first + 1).boxes[0])]
    out, found = stage.process(scene.frame(first), bg, mask, regions, tracks)
    assert len(found.heads) == 1
    assert abs(found.heads[0].x - (gt.at(first + 1).boxes[0, 0] + gt.at(first + 1).boxes[0, 2] / 2)) < 12
    assert len(found.shapes) == 1 and found.shapes[0].track_id == 1
    assert found.hypotheses == () and found.hypotheses_by_track == {}
    assert len(out) == len(regions)


def test_people_stage_offers_a_hypothesis_for_an_uncovered_person(walker):
    scene, gt, first = walker
    bg = scene.background
    stage = PeopleStage(PeopleConfig(enabled=True, hypotheses=True, heads=False))
    # two frames with a measured track: the shape is born, then agrees with its track
    for i in (first, first + 1):
        stage.process(scene.frame(i), bg, None, [], [_track(5, gt.at(i + 1).boxes[0])])
    # next frame: the motion detector lost the person (no regions) and the tracker lost the track
    out, found = stage.process(scene.frame(first + 2), bg, None, [], [])
    # the hypothesis is offered to track 5 only (the pipeline hands it to that lost track); it is
    # not a region, so it can never start a new track
    assert out == []
    assert list(found.hypotheses_by_track) == [5]
    (hyp,) = found.hypotheses
    assert hyp.score == 0.5 and found.hypotheses_by_track[5] == hyp
    assert iou_matrix(hyp.box.as_array()[None], gt.at(first + 3).boxes)[0, 0] > 0.6


def test_no_hypothesis_for_a_shape_never_checked_against_its_track(walker):
    scene, gt, first = walker
    stage = PeopleStage(PeopleConfig(enabled=True, hypotheses=True, heads=False))
    stage.process(scene.frame(first), scene.background, None, [], [_track(5, gt.at(first + 1).boxes[0])])
    out, found = stage.process(scene.frame(first + 1), scene.background, None, [], [])
    assert out == [] and found.hypotheses_by_track == {}


def test_people_config_validates():
    from motiontrack.errors import ConfigError

    with pytest.raises(ConfigError, match="hog"):
        PeopleConfig(hog="sometimes")
    with pytest.raises(ConfigError, match="min_support"):
        PeopleConfig(min_support=2.0)


def test_draw_people_marks_outlines_heads_normals_and_hypotheses(walker):
    from motiontrack.render.people import draw_people
    from motiontrack.types import PeopleFrame

    scene, gt, first = walker
    bg = scene.background
    stage = PeopleStage(PeopleConfig(enabled=True))
    mask = scene.foreground_mask(first)
    from motiontrack.motion.regions import components

    img = scene.frame(first)
    _, found = stage.process(img, bg, mask, components(mask), [_track(1, gt.at(first + 1).boxes[0])])
    drawn = draw_people(img, found, control_points=True, normals=True)
    assert drawn.shape == img.shape and not np.array_equal(drawn, img)
    assert np.array_equal(img, scene.frame(first))  # input untouched
    changed = np.any(drawn != img, axis=2)
    ys, xs = np.nonzero(changed)
    x, y, w, h = gt.at(first + 1).boxes[0]
    assert x - 15 <= xs.mean() <= x + w + 15 and y - 15 <= ys.mean() <= y + h + 15
    assert np.array_equal(draw_people(img, PeopleFrame()), img)  # nothing to draw


# ------------------------------------------------------- regions cut off by the image border
def _shape(box, support=0.45, visible=0.5, coasting=0, tid=1):
    z = np.zeros((4, 2))
    return FittedShape(track_id=tid, outline=z, control=z, box=Box(*map(float, box)),
                       support=support, coasting=coasting, normals=z, visible=visible)


def _reg(box):
    from motiontrack.types import Region

    b = Box(*map(float, box))
    return Region(box=b, centroid=b.center, area=b.area)


def test_region_at_the_border_takes_the_outline_beyond_it():
    from motiontrack.people.stage import _extend_at_border

    W, H = 640, 480
    region = _reg((0, 296, 19, 75))           # a person entering on the left, cut at x = 0
    shape = _shape((-10, 298, 27, 77))        # the outline reaches 10 px past the border
    (out,) = _extend_at_border([shape], [region], W, H, 0.7)
    # only the cut side moves, to the outline's edge; top, bottom and right are the region's
    assert (out.box.x, out.box.y, out.box.x2, out.box.y2) == (-10, 296, 19, 371)
    assert out.area == region.area
    # right border, the same
    (out,) = _extend_at_border([_shape((630, 100, 20, 60))], [_reg((628, 98, 12, 64))], W, H, 0.7)
    assert (out.box.x, out.box.x2) == (628, 650)


@pytest.mark.parametrize("case", ["inside", "weak", "coasting", "no_overlap", "not_past"])
def test_border_extension_needs_a_cut_region_and_a_good_outline(case):
    from motiontrack.people.stage import _extend_at_border

    region, shape = _reg((0, 296, 19, 75)), dict(box=(-10, 298, 27, 77))
    if case == "inside":          # the region does not touch the border
        region = _reg((40, 296, 19, 75))
        shape = dict(box=(30, 298, 27, 77))
    elif case == "weak":          # edges on 0.6 of the visible points < 0.7
        shape["support"] = 0.3
    elif case == "coasting":      # a predicted, not fitted, outline
        shape["coasting"] = 1
    elif case == "no_overlap":    # someone else's outline
        shape = dict(box=(-10, 150, 27, 77))
    elif case == "not_past":      # the outline ends inside the image
        shape = dict(box=(0, 298, 22, 77))
    assert _extend_at_border([_shape(**shape)], [region], 640, 480, 0.7) == [region]


@pytest.mark.parametrize("scene", ["column", "crossing"])
@pytest.mark.slow
def test_shape_tracker_raises_recall_on_column_and_crossing(scene):
    # With the people preset, switching the active shape tracker on raises recall (CLEAR, IoU
    # 0.5) and costs at most 0.02 precision on synthetic types 3 and 4.
    # Measured: column 0.986 -> 0.993 (the person entering across the border is extended past it
    # by the outline). The column case uses MOG2 with the 5x5 blur and its shadow test alone
    # (shadow_inside off), which cuts the entering person at the border; the default KNN
    # detector, or MOG2 giving back the shadow pixels inside the person, sees all of them there
    # (recall 0.993 with or without shapes). Crossing seed 1 (the merged blob is split along the outlines): recall
    # 0.964 -> 0.989; seed 0 does not merge the two walkers for long enough to show it (0.995
    # either way), so the test tracks the seed where the two merge.
    from motiontrack.config import load_config
    from motiontrack.evaluate.mot import evaluate_tracking
    from motiontrack.pipeline import run
    from motiontrack.synth import parse_synth_spec

    spec = "synth:column" if scene == "column" else "synth:crossing?seed=1"

    def score(spec: str, shapes: bool) -> tuple[float, float]:
        gt = parse_synth_spec(spec).ground_truth()
        detector = (["motion.method=mog2", "preprocess.blur_kernel=5",
                     "motion.mog2.shadow_inside=false"] if scene == "column" else [])
        cfg = load_config(None, ["people.enabled=true", f"people.shapes={str(shapes).lower()}",
                                 *detector])
        res = evaluate_tracking(gt, tracks_of(run(spec, cfg)), ignore_zero_marked=True)
        tp, fp, fn = res["TP"], res["FP"], res["FN"]
        return tp / (tp + fn), tp / (tp + fp)

    (r0, p0), (r1, p1) = (score(spec, shapes) for shapes in (False, True))
    assert r1 > r0
    assert p1 >= p0 - 0.02


def test_difference_image_is_the_largest_channel_difference():
    from motiontrack.people.shape_tracker import difference_image

    rng = np.random.default_rng(0)
    a, b = (rng.integers(0, 256, (30, 40, 3), dtype=np.uint8) for _ in range(2))
    want = np.abs(a.astype(int) - b.astype(int)).max(axis=2)
    np.testing.assert_array_equal(difference_image(a, b), want)
    grey = np.abs(a[..., 0].astype(int) - b[..., 0].astype(int))
    np.testing.assert_array_equal(difference_image(a[..., 0], b[..., 0]), grey)


def _crossing_shapes(group):
    """The shapes of the two people of the synthetic ``crossing`` scene while they pass each
    other (the nearer one hides part of the other), fitted with people grouped by ``group``
    (None: the tracker's own grouping), and how often a group had to be fitted again."""
    from motiontrack.synth import make_scene

    scene = make_scene("crossing", seed=0)
    gt = scene.ground_truth()
    st = ShapeTracker(load_default_model())
    if group is not None:
        st._group = group
    measure, refits = st._measure_group, []

    def counted(ids, *args):
        kept = measure(ids, *args)
        refits.append(kept < len(ids))
        return kept

    st._measure_group = counted
    out = []
    for i in range(150, 230):
        a = gt.at(i + 1)
        tracks = [_track(int(t), b) for t, b in zip(a.ids, a.boxes)]
        out.append(st.update(scene.frame(i), scene.background, [], tracks,
                             mask=scene.foreground_mask(i)))
    return out, sum(refits)


def test_people_fitted_together_get_the_fits_of_one_at_a_time():
    one_by_one, _ = _crossing_shapes(lambda order, boxes: [order[0]])
    grouped, _ = _crossing_shapes(None)
    # everyone in one group: a person the fitted outline of a nearer one hides is fitted again
    together, refits = _crossing_shapes(lambda order, boxes: list(order))
    assert refits > 0
    assert sum(map(len, one_by_one)) == 160
    for run in (grouped, together):
        for a_frame, b_frame in zip(one_by_one, run):
            assert len(a_frame) == len(b_frame)
            for a, b in zip(a_frame, b_frame):
                assert (a.track_id, a.box, a.support, a.visible, a.coasting, a.search) \
                    == (b.track_id, b.box, b.support, b.visible, b.coasting, b.search)
                for name in ("outline", "control", "normals"):
                    np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
