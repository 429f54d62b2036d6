"""Synthetic scenes: determinism, exact ground truth, occlusion, lighting, spec parsing."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from motiontrack.errors import ConfigError
from motiontrack.synth import (
    MASK_PERSON,
    MASK_SHADOW,
    SCENES,
    Column,
    Person,
    SyntheticScene,
    make_scene,
    parse_synth_spec,
)
from motiontrack.synth.render import render_person
from motiontrack.types import Annotations

REQUIRED = ("walker", "runner", "column", "crossing", "crowd", "lighting")


def _bbox(mask: np.ndarray) -> tuple[int, int, int, int] | None:
    """Tight (x, y, w, h) of the non-zero pixels of a 2-D mask."""
    ys, xs = np.nonzero(mask)
    if xs.size == 0:
        return None
    return int(xs.min()), int(ys.min()), int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1)


def _intersect(a, b) -> bool:
    return a[0] < b[0] + b[2] and b[0] < a[0] + a[2] and a[1] < b[1] + b[3] and b[1] < a[1] + a[3]


def _runs(values) -> list[int]:
    """Lengths of runs of consecutive integers in a sorted sequence."""
    v = np.asarray(sorted(values), dtype=np.int64)
    if v.size == 0:
        return []
    cuts = np.flatnonzero(np.diff(v) != 1) + 1
    return [len(g) for g in np.split(v, cuts)]


@pytest.fixture(scope="module")
def scenes() -> dict[str, SyntheticScene]:
    """One default scene of each type (ground truth cached inside the objects)."""
    return {name: make_scene(name, seed=0) for name in SCENES}


# --------------------------------------------------------------------------- catalogue & basics
def test_required_scene_types_exist():
    assert set(REQUIRED) <= set(SCENES)


@pytest.mark.parametrize("name", REQUIRED)
def test_defaults_and_frame_format(scenes, name):
    s = scenes[name]
    assert (s.width, s.height, s.fps) == (640, 480, 25.0)
    assert 120 <= s.n_frames <= 250
    img = s.frame(s.n_frames // 2)
    assert img.shape == (480, 640, 3) and img.dtype == np.uint8
    m = s.foreground_mask(s.n_frames // 2)
    assert m.shape == (480, 640) and m.dtype == np.uint8
    assert set(np.unique(m)) <= {0, MASK_SHADOW, MASK_PERSON}


@pytest.mark.parametrize("i", [-1, 10_000])
def test_frame_index_out_of_range(scenes, i):
    with pytest.raises(IndexError, match="frame index"):
        scenes["walker"].frame(i)


def test_frame_is_a_fresh_writable_array(scenes):
    s = scenes["walker"]
    a = s.frame(40)
    a[:] = 0  # the caller may draw on it ...
    assert s.frame(40).any()  # ... without changing what the scene renders next time
    assert not s.background.flags.writeable


# --------------------------------------------------------------------------------- determinism
@pytest.mark.parametrize("name", REQUIRED)
def test_same_seed_same_frames_and_gt(name):
    a, b = make_scene(name, seed=7), make_scene(name, seed=7)
    # random access in different orders gives the same pixels
    for i in (a.n_frames - 1, 0, 100, 17):
        assert np.array_equal(a.frame(i), b.frame(i)), i
    for i in (100, 17, a.n_frames - 1):
        assert np.array_equal(a.frame(i), b.frame(i)), i
        assert np.array_equal(a.foreground_mask(i), b.foreground_mask(i)), i
    ga, gb = a.ground_truth(), b.ground_truth()
    for col in ("frames", "ids", "boxes", "visibility", "consider"):
        assert np.array_equal(getattr(ga, col), getattr(gb, col)), col


@pytest.mark.parametrize("name", REQUIRED)
def test_different_seed_differs(name):
    a, b = make_scene(name, seed=1), make_scene(name, seed=2)
    assert not np.array_equal(a.frame(5), b.frame(5))  # background and noise
    ga, gb = a.ground_truth(), b.ground_truth()
    assert len(ga) != len(gb) or not np.array_equal(ga.boxes, gb.boxes)


def test_consecutive_frames_have_fresh_noise(scenes):
    s = scenes["walker"]
    d = s.frame(1).astype(np.int16) - s.frame(2).astype(np.int16)  # empty frames: only noise
    # the difference of two independent N(0, 3.5²) samples has std 3.5·√2
    assert d.std() == pytest.approx(3.5 * math.sqrt(2), rel=0.15)


@pytest.mark.parametrize("sigma", [0.0, 2.0, 3.5, 6.0])
def test_noise_level(sigma):
    s = make_scene("walker", seed=3, noise=sigma)
    d = s.frame(3).astype(np.float64) - s.background  # frame 3 is empty
    assert d.std() == pytest.approx(sigma, abs=0.15)


# ------------------------------------------------------------------------------- ground truth
@pytest.mark.parametrize("name", REQUIRED)
def test_gt_conventions(scenes, name):
    s = scenes[name]
    gt = s.ground_truth()
    assert isinstance(gt, Annotations) and len(gt) > 0
    assert gt.frames.min() >= 1 and gt.frames.max() <= s.n_frames  # 1-based frame numbers
    assert sorted(np.unique(gt.ids).tolist()) == list(range(1, len(s.people) + 1))
    assert np.all(gt.classes == 1)
    assert np.all((gt.visibility >= 0) & (gt.visibility <= 1))
    assert np.array_equal(gt.consider, gt.visibility >= 0.5)
    assert np.all(gt.boxes[:, 2:] > 0)
    # at most one row per (frame, id)
    keys = gt.frames * 1000 + gt.ids
    assert len(np.unique(keys)) == len(gt)
    assert np.all(np.diff(keys) > 0)  # sorted by frame, then id
    # person heights in the intended range
    assert 55 <= gt.boxes[:, 3].min() and gt.boxes[:, 3].max() <= 125


@pytest.mark.parametrize("name", REQUIRED)
@pytest.mark.parametrize("seed", [0, 5])
def test_empty_background_before_anyone_enters(name, seed):
    s = make_scene(name, seed=seed)
    gt = s.ground_truth()
    assert gt.frames.min() >= 16  # >= 15 frames (numbers 1..15) of empty background
    for i in (0, 7, 14):
        assert not s.foreground_mask(i).any()


@pytest.mark.parametrize("name", ["walker", "runner", "column", "lighting", "crossing", "crowd"])
def test_gt_box_encloses_rendered_pixels(scenes, name):
    """Fully visible and apart from others: the gt box is the bounding box of its mask pixels."""
    s = scenes[name]
    gt = s.ground_truth()
    checked = 0
    for f, rows in gt.by_frame().items():
        if f % 3:  # every third frame suffices
            continue
        mask = None
        for r in rows:
            x, y, w, h = gt.boxes[r].astype(int)
            grown = (x - 2, y - 2, w + 4, h + 4)
            if gt.visibility[r] < 1.0 or any(
                _intersect(grown, gt.boxes[q]) for q in rows if q != r
            ):
                continue
            if mask is None:
                mask = s.foreground_mask(f - 1) == MASK_PERSON
            x1, y1 = max(x - 2, 0), max(y - 2, 0)
            got = _bbox(mask[y1:y + h + 2, x1:x + w + 2])
            assert got is not None
            got = np.asarray(got) + [x1, y1, 0, 0]
            assert np.array_equal(got, gt.boxes[r]), (f, got, gt.boxes[r])  # exact, not just ±1 px
            checked += 1
    assert checked >= 5


@pytest.mark.parametrize("name", ["walker", "crowd"])
def test_rows_exactly_when_a_person_is_in_the_image(scenes, name):
    s = scenes[name]
    gt = s.ground_truth()
    with_rows = set(gt.frames.tolist())
    for f in range(1, s.n_frames + 1, 4):
        visible_pixels = (s.foreground_mask(f - 1) == MASK_PERSON).any()
        if visible_pixels:
            assert f in with_rows, f
        if f not in with_rows:
            assert not visible_pixels, f


def test_visible_pixels_add_up_hand_built():
    """Two standing people, one partly behind the other and partly outside the image.

    Sum over people of visibility × (own pixels) must equal the mask's person pixel count.
    """
    back = Person(id=1, x0=10.0, y0=300.0, vx=0.0, vy=0.0, height=90.0)  # cut by the left border
    front = Person(id=2, x0=40.0, y0=330.0, vx=0.0, vy=0.0, height=100.0, shirt=(200, 80, 30))
    s = SyntheticScene("hand", seed=0, width=320, height=360, fps=25.0, n_frames=3,
                       people=(back, front), noise=0.0)
    gt = s.ground_truth()
    assert gt.frames.tolist() == [1, 1, 2, 2, 3, 3]
    rows = gt.at(1)
    own = {p.id: int((render_person(p, 0).labels > 0).sum()) for p in (back, front)}
    visible = sum(v * own[int(k)] for k, v in zip(rows.ids, rows.visibility))
    assert visible == pytest.approx(int((s.foreground_mask(0) == MASK_PERSON).sum()))
    vis = dict(zip(rows.ids.tolist(), rows.visibility.tolist()))
    assert vis[2] == 1.0 and 0.0 < vis[1] < 1.0
    # the back person's box is its full extent, reaching beyond the left border
    assert rows.boxes[rows.ids == 1][0, 0] < 0


def test_fully_outside_is_no_row_and_partly_inside_is_partly_visible():
    # Person standing with its foot point 30 px left of the image: only the front arm/leg may show.
    p = Person(id=1, x0=-60.0, y0=200.0, vx=1.0, vy=0.0, height=80.0)
    s = SyntheticScene("edge", seed=0, width=200, height=240, fps=25.0, n_frames=90,
                       people=(p,), noise=0.0)
    gt = s.ground_truth()
    assert gt.frames.min() > 1  # frame 1: entirely outside, no row
    first = gt.at(int(gt.frames.min()))
    assert 0.0 < first.visibility[0] < 0.5 and not first.consider[0]
    assert first.boxes[0, 0] < 0  # full extent, not clipped to the image
    inside = gt.select((gt.boxes[:, 0] >= 0) & (gt.boxes[:, 0] + gt.boxes[:, 2] <= 200))
    assert np.all(inside.visibility == 1.0)


def test_no_people_gives_empty_gt():
    s = SyntheticScene("empty", seed=0, width=64, height=64, fps=25.0, n_frames=4)
    gt = s.ground_truth()
    assert len(gt) == 0 and gt.boxes.shape == (0, 4)
    assert not s.foreground_mask(3).any()
    assert s.describe()["events"] == [{"frames": [1, 4], "what": "empty background only"}]


def test_short_override_before_entry_gives_empty_gt():
    s = make_scene("walker", n_frames=10)
    assert s.n_frames == 10 and len(s.ground_truth()) == 0


@pytest.mark.parametrize("gait", ["walk", "run"])
def test_sprite_never_clips_the_figure(gait):
    """The full extent must fit in the sprite, or gt boxes would be silently cut."""
    rng = np.random.default_rng(0)
    for _ in range(40):
        p = Person(id=1, x0=100.0, y0=300.0, vx=float(rng.uniform(-8, 8)) or 1.0, vy=0.0,
                   height=float(rng.uniform(20, 160)), gait=gait,
                   phase0=float(rng.uniform(0, 2 * math.pi)))
        lab = render_person(p, int(rng.integers(0, 200))).labels
        border = np.concatenate([lab[0], lab[-1], lab[:, 0], lab[:, -1]])
        assert not border.any()


# ----------------------------------------------------------------------------- scene contents
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_column_hides_the_person_for_at_least_10_frames(seed):
    s = make_scene("column", seed=seed)
    gt = s.ground_truth()
    hidden = gt.frames[gt.visibility == 0]
    assert max(_runs(hidden), default=0) >= 10
    for f in hidden[::5]:
        assert not (s.foreground_mask(int(f) - 1) == MASK_PERSON).any()
    # seen before and after the column
    assert (gt.frames[gt.visibility == 1] < hidden.min()).any()
    assert (gt.frames[gt.visibility == 1] > hidden.max()).any()


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4, 5])
def test_crossing_boxes_overlap_for_at_least_10_frames(seed):
    s = make_scene("crossing", seed=seed)
    a, b = s.people
    assert np.sign(a.vx) == -np.sign(b.vx)  # opposite directions
    assert abs(a.y0 - b.y0) >= 0.05 * s.height  # slightly different heights in the image
    gt = s.ground_truth()
    overlap = [f for f, r in gt.by_frame().items()
               if len(r) == 2 and _intersect(gt.boxes[r[0]], gt.boxes[r[1]])]
    assert max(_runs(overlap), default=0) >= 10
    # the person further away is partly hidden while they cross
    assert (gt.visibility[gt.ids == (1 if a.y0 < b.y0 else 2)] < 1).any()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_crowd_size_and_distinct_colours(seed):
    s = make_scene("crowd", seed=seed)
    assert 5 <= len(s.people) <= 8
    assert len({p.shirt for p in s.people}) == len(s.people)
    assert len(np.unique(s.ground_truth().ids)) == len(s.people)


@pytest.mark.parametrize(
    "name, lo, hi",
    [("walker", 1.5, 3.0), ("runner", 5.0, 8.0), ("column", 1.5, 3.0), ("crossing", 1.5, 3.0)],
)
def test_speeds(name, lo, hi):
    for seed in range(4):
        for p in make_scene(name, seed=seed).people:
            assert lo <= p.speed <= hi


@pytest.mark.parametrize("name", ["walker", "runner"])
def test_walker_crosses_the_image(scenes, name):
    s = scenes[name]
    gt = s.ground_truth()
    cx = gt.boxes[:, 0] + gt.boxes[:, 2] / 2
    assert cx.max() - cx.min() >= 0.85 * s.width


def test_people_stand_out_from_the_background():
    s = make_scene("crowd", seed=0, noise=0.0)
    f = 200
    m = s.foreground_mask(f) == MASK_PERSON
    gray = cv2.cvtColor(s.frame(f), cv2.COLOR_BGR2GRAY).astype(np.int16)
    bg = cv2.cvtColor(np.ascontiguousarray(s.background), cv2.COLOR_BGR2GRAY).astype(np.int16)
    assert np.median(np.abs(gray - bg)[m]) >= 25


def test_shadows():
    on = make_scene("walker", seed=0, shadows=True, noise=0.0)
    off = make_scene("walker", seed=0, noise=0.0)
    i = 120
    m = on.foreground_mask(i)
    shadow = m == MASK_SHADOW
    assert shadow.sum() > 100
    assert not (off.foreground_mask(i) == MASK_SHADOW).any()
    # shadow pixels are darker than the background, people pixels are identical either way
    assert np.all(on.frame(i)[shadow] < on.background[shadow])
    assert np.array_equal(m == MASK_PERSON, off.foreground_mask(i) == MASK_PERSON)
    # the shadow lies on the ground at the person's feet (near the box bottom)
    gt = on.ground_truth().at(i + 1)
    y_bottom = gt.boxes[0, 1] + gt.boxes[0, 3]
    assert abs(np.nonzero(shadow)[0].max() - y_bottom) <= 12


def test_lighting_gradual_and_sudden():
    s = make_scene("lighting", seed=0, noise=0.0)
    L = s.lighting
    assert L is not None
    ill = s.describe()["illumination"]
    assert ill["sudden"]["frame"] == L.jump_at + 1 and ill["gradual"]["gain"] == L.ramp_gain

    def mean(i):
        return float(s.frame(i).mean())

    base = mean(0)
    # gradual: each frame of the ramp changes the brightness by well under 1 %
    steps = [abs(mean(i + 1) / mean(i) - 1) for i in range(L.ramp_start, L.ramp_end, 7)]
    assert max(steps) < 0.01
    assert mean(L.ramp_end) / base == pytest.approx(L.ramp_gain, abs=0.03)
    # sudden: one frame, about +20 % (a little less where bright pixels saturate)
    jump = mean(L.jump_at) / mean(L.jump_at - 1)
    assert 1.12 <= jump <= L.jump_factor + 0.01
    # illumination is not motion: the masks are those of the same scene without lighting changes
    flat = make_scene("lighting", seed=0, noise=0.0, illumination=False)
    for i in (L.ramp_end, L.jump_at):
        assert np.array_equal(s.foreground_mask(i), flat.foreground_mask(i))


def test_illumination_override():
    assert make_scene("walker").lighting is None
    assert make_scene("walker", illumination=True).lighting is not None
    assert make_scene("lighting", illumination=False).lighting is None


@pytest.mark.parametrize("w, h", [(320, 240), (1280, 720)])
def test_size_override_scales_people(w, h):
    s = make_scene("walker", seed=0, width=w, height=h, n_frames=150)
    img = s.frame(s.n_frames - 1)
    assert img.shape == (h, w, 3)
    hts = s.ground_truth().boxes[:, 3]
    assert hts.min() >= 84 * h / 480 - 3 and hts.max() <= 104 * h / 480 + 3


def test_describe(scenes):
    d = scenes["column"].describe()
    for key in ("name", "seed", "size", "fps", "n_frames", "people", "events", "column", "spec"):
        assert key in d
    assert d["size"] == [640, 480] and d["people"][0]["id"] == 1
    assert any("hidden" in e["what"] for e in d["events"])
    assert d["events"][0]["what"] == "empty background"


# -------------------------------------------------------------------------------- spec parsing
@pytest.mark.parametrize(
    "spec, expected",
    [
        ("synth:crossing", dict(name="crossing", seed=0, n_frames=250, shadows=False)),
        ("synth:crossing?seed=3&n_frames=200&shadows=true",
         dict(name="crossing", seed=3, n_frames=200, shadows=True)),
        ("synth:walker?width=320&height=240&fps=10&noise=0&illumination=on",
         dict(name="walker", width=320, height=240, fps=10.0, noise=0.0)),
        ("synth:runner?shadows=0&n_frames=100.0", dict(name="runner", shadows=False, n_frames=100)),
        ("synth:crowd?", dict(name="crowd", seed=0)),
    ],
)
def test_parse_synth_spec_good(spec, expected):
    s = parse_synth_spec(spec)
    for k, v in expected.items():
        assert getattr(s, k) == v, k


@pytest.mark.parametrize(
    "spec, message",
    [
        ("crossing", "synth:NAME"),
        ("synth:", "no scene name"),
        ("synth:nope", "valid names: walker, runner, column, crossing, crowd, lighting"),
        ("synth:walker?foo=1", "unknown synthetic scene parameter 'foo'"),
        ("synth:walker?seed=x", "seed"),
        ("synth:walker?seed=-1", "seed"),
        ("synth:walker?n_frames=0", "n_frames must be an integer in"),
        ("synth:walker?n_frames=2.5", "n_frames"),
        ("synth:walker?width=10", "width"),
        ("synth:walker?noise=-1", "noise"),
        ("synth:walker?fps=nan", "fps"),
        ("synth:walker?shadows=maybe", "shadows must be true or false"),
        ("synth:walker?seed=1&seed=2", "given twice"),
        ("synth:walker?noise", "key=value"),
    ],
)
def test_parse_synth_spec_bad(spec, message):
    with pytest.raises(ConfigError) as exc:
        parse_synth_spec(spec)
    assert message in str(exc.value)


@pytest.mark.parametrize(
    "name, kwargs, message",
    [
        ("bogus", {}, "valid names: walker, runner"),
        ("walker", {"speed": 3}, "unknown synthetic scene parameter(s) speed"),
        ("walker", {"shadows": "yes"}, "shadows must be true or false"),
        ("walker", {"n_frames": True}, "n_frames"),
        ("walker", {"seed": -2}, "seed"),
    ],
)
def test_make_scene_bad(name, kwargs, message):
    with pytest.raises(ConfigError) as exc:
        make_scene(name, **kwargs)
    assert message in str(exc.value)


def test_spec_round_trip():
    s = make_scene("crossing", seed=4, n_frames=60, shadows=True, noise=2.0)
    t = parse_synth_spec(s.spec)
    assert t.spec == s.spec
    assert np.array_equal(s.frame(59), t.frame(59))


def test_column_must_be_valid():
    with pytest.raises(ValueError, match="w > 0"):
        Column(x=0, y=0, w=0, h=10)


def test_ground_truth_round_trips_through_mot_csv(tmp_path, scenes):
    from motiontrack.io.mot import read_mot, write_mot

    gt = scenes["crossing"].ground_truth()
    write_mot(gt, tmp_path / "gt.txt", kind="gt")
    back = read_mot(tmp_path / "gt.txt")
    assert np.array_equal(back.frames, gt.frames) and np.array_equal(back.ids, gt.ids)
    assert np.array_equal(back.boxes, gt.boxes) and np.array_equal(back.consider, gt.consider)
    assert np.allclose(back.visibility, gt.visibility, atol=1e-4)
    assert np.all(back.classes == 1)


def test_pickles_without_caches_and_renders_the_same():
    import pickle

    s = make_scene("crossing", seed=2, n_frames=80)
    a = s.frame(np.int64(79))  # numpy integers are valid indices
    s.ground_truth()
    blob = pickle.dumps(s)
    assert len(blob) < 100_000  # background, noise pool and gt are not shipped
    t = pickle.loads(blob)
    assert np.array_equal(t.frame(79), a)
    assert np.array_equal(t.ground_truth().boxes, s.ground_truth().boxes)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(id=0), "id must be >= 1"),
        (dict(gait="crawl"), "gait must be one of"),
        (dict(height=3.0), "height must be >= 8"),
        (dict(vx=float("nan")), "vx must be finite"),
        (dict(horizon=400.0), "horizon must lie above"),
        (dict(shirt=(0, 0, 300)), "shirt must be 3 BGR values"),
    ],
)
def test_person_validates_itself(kwargs, message):
    base = dict(id=1, x0=0.0, y0=300.0, vx=1.0, vy=0.0, height=80.0)
    with pytest.raises(ValueError, match=message):
        Person(**{**base, **kwargs})


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(n_frames=0), "n_frames must be >= 1"),
        (dict(width=8), "at least 16x16"),
        (dict(noise=-1.0), "noise must be in"),
        (dict(people=(Person(1, 0, 300, 1, 0, 80), Person(1, 5, 300, 1, 0, 80))), "unique"),
    ],
)
def test_scene_validates_itself(kwargs, message):
    base = dict(name="x", seed=0, width=64, height=64, fps=25.0, n_frames=5)
    with pytest.raises(ValueError, match=message):
        SyntheticScene(**{**base, **kwargs})
