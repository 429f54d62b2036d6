"""The annotated video's picture: mask inset placement, text proportional to the frame, distinct
track colours, the legend of box kinds (render/annotate.py, render/colors.py, run/processors.py)."""

from __future__ import annotations

import numpy as np
import pytest

from motiontrack.config import PipelineConfig, apply_overrides, load_config
from motiontrack.errors import ConfigError
from motiontrack.render.annotate import annotate_frame, draw_tracks, line_width
from motiontrack.render.colors import BASE_COLORS, TrackColors, palette_color
from motiontrack.run.processors import track_legend
from motiontrack.types import Box, Track, TrackState


def _track(tid, x, y, w=20, h=40, seen=True):
    return Track(id=tid, box=Box(x, y, w, h), state=TrackState.CONFIRMED,
                 time_since_update=0 if seen else 3)


# ------------------------------------------------------------------------------- mask inset
@pytest.mark.parametrize("corner, rows, cols", [
    # 640x480 frame, mask 4:3, inset 0.2 → 128x96 px
    ("top-left", slice(0, 96), slice(0, 128)),
    ("top-right", slice(0, 96), slice(512, 640)),
    ("bottom-left", slice(384, 480), slice(0, 128)),
    ("bottom-right", slice(384, 480), slice(512, 640)),
])
def test_mask_inset_goes_to_the_chosen_corner_at_the_chosen_width(corner, rows, cols):
    frame = np.full((480, 640, 3), 60, np.uint8)
    mask = np.full((240, 320), 255, np.uint8)
    img = annotate_frame(frame, [], mask=mask, inset=corner, inset_scale=0.2)
    inset = np.zeros((480, 640), bool)
    inset[rows, cols] = True
    assert (img[inset] == 255).all()          # the white mask fills exactly that corner
    assert (img[~inset] == 60).all()          # and nothing else changed


def test_no_inset_by_default_so_no_corner_of_the_scene_is_hidden():
    cfg = PipelineConfig()
    assert cfg.output.inset == "none"
    frame = np.full((480, 640, 3), 60, np.uint8)
    img = annotate_frame(frame, [], mask=np.full((480, 640), 255, np.uint8),
                         inset=cfg.output.inset, inset_scale=cfg.output.inset_scale)
    assert (img == 60).all()


def test_a_wider_inset_scale_gives_a_wider_inset():
    frame = np.zeros((480, 640, 3), np.uint8)
    img = annotate_frame(frame, [], mask=np.full((480, 640), 255, np.uint8), inset="top-left",
                         inset_scale=0.5)
    assert (img[0, :320] == 255).all() and (img[0, 321:] == 0).all()     # 0.5 x 640 = 320 px


@pytest.mark.parametrize("override, needle", [
    ("output.inset=middle", "output.inset must be one of"),
    ("output.inset_scale=0.9", "output.inset_scale must be in [0.05, 0.5]"),
])
def test_bad_inset_settings_are_config_errors(override, needle):
    with pytest.raises(ConfigError) as err:
        apply_overrides(PipelineConfig(), [override])
    assert needle in str(err.value)


def test_inset_keys_read_from_the_config():
    cfg = load_config(None, ["output.inset=bottom-right", "output.inset_scale=0.1"])
    assert (cfg.output.inset, cfg.output.inset_scale) == ("bottom-right", 0.1)


# ------------------------------------------------------------------------- text size, lines
def _label_height(w, h):
    """Rows (px) of the id label of one track whose box top is mid-frame (black frame)."""
    img = np.zeros((h, w, 3), np.uint8)
    t = _track(7, w * 0.4, h * 0.5, w * 0.05, h * 0.2)
    colors = {7: (0, 255, 0)}
    draw_tracks(img, [t], trail=0, colors=colors)
    top = int(round(t.box.y)) - line_width(img.shape)     # above the box's top edge
    rows = np.flatnonzero((img[:top] == (0, 255, 0)).all(axis=2).any(axis=1))
    return rows.max() - rows.min() + 1


def test_id_labels_are_as_tall_relative_to_the_frame_at_320x240_and_1920x1080():
    small, large = _label_height(320, 240) / 240, _label_height(1920, 1080) / 1080
    assert small == pytest.approx(large, rel=0.2)
    assert 0.015 < large < 0.05                  # readable, not a banner


def test_box_lines_thicken_with_the_frame_and_predictions_are_thinner():
    assert line_width((240, 320)) == 2 and line_width((1080, 1920)) == 4
    assert line_width((1080, 1920), seen=False) == 2 and line_width((240, 320), seen=False) == 1


# ---------------------------------------------------------------------------- track colours
def test_visible_tracks_never_share_a_colour_and_keep_theirs_while_visible():
    rng = np.random.default_rng(0)
    colors = TrackColors()
    alive: dict[int, int] = {}       # id → frames left
    next_id, previous = 1, {}
    for frame in range(400):
        # up to ~60 tracks at once: many more than the 12 base colours
        for _ in range(rng.poisson(3)):
            alive[next_id] = int(rng.integers(5, 80))
            next_id += 1
        visible = [i for i in alive if rng.random() > 0.1]   # a tenth unseen for a frame
        got = colors.assign(visible)
        assert set(got) == set(visible)
        assert len(set(got.values())) == len(got), f"frame {frame}: shared colour"
        for i in visible:
            if i in previous:
                assert got[i] == previous[i], f"frame {frame}: track {i} changed colour"
        previous = got
        alive = {i: n - 1 for i, n in alive.items() if n > 1}
    assert next_id > 300


def test_a_returning_track_gets_its_colour_back_unless_another_holds_it():
    colors = TrackColors()
    first = colors.assign([1, 2])
    colors.assign([2])                          # 1 unseen for a frame
    assert colors.assign([1, 2]) == first       # 1 returns to its colour
    colors.assign([2, 3])
    # 3 took the colour that had gone unused longest, not 1's
    assert colors.assign([1, 2, 3])[1] == first[1]


def test_a_new_track_takes_the_colour_unused_longest():
    colors = TrackColors()
    c1 = colors.assign([1])[1]
    c2 = colors.assign([2])[2]                  # 1 gone: 2 does not get 1's colour at once
    assert c2 != c1
    seen = {c1, c2}
    for tid in range(3, BASE_COLORS + 1):
        seen.add(colors.assign([tid])[tid])
    assert len(seen) == BASE_COLORS             # every base colour before any is reused


def test_palette_colours_are_all_different():
    colours = [palette_color(k) for k in range(1000)]
    assert len(set(colours)) == 1000
    assert all(len(set(c)) > 1 for c in colours[:3 * BASE_COLORS])   # none of them grey


def test_many_tracks_in_one_annotated_frame_have_distinct_colours():
    frame = np.zeros((480, 640, 3), np.uint8)
    tracks = [_track(tid, 10 + 60 * (k % 10), 40 + 100 * (k // 10), 30, 50)
              for k, tid in enumerate(range(100, 4100, 100))]          # 40 ids, all ≡ 0 mod 100
    img = annotate_frame(frame, tracks, trail=0)
    # the colour of each box's left edge, half way down
    edge = {tuple(int(v) for v in img[int(t.box.y + 25), int(t.box.x)]) for t in tracks}
    assert len(edge) == len(tracks)


# ---------------------------------------------------------------------------------- legend
def test_legend_names_the_box_kinds_the_run_draws():
    cfg = PipelineConfig()
    assert track_legend(cfg) == (("track", "track (id, trail)"), ("region", "motion region"))
    assert track_legend(cfg, external=True)[-1] == ("region", "detection")
    lost = apply_overrides(cfg, ["tracker.output_lost=true"])
    assert ("predicted", "track, not seen (predicted)") in track_legend(lost)
    people = apply_overrides(cfg, ["people.enabled=true", "people.hypotheses=true"])
    assert {"head", "hypothesis"} <= {style for style, _ in track_legend(people)}


def test_legend_is_drawn_bottom_left_or_beside_a_bottom_left_inset():
    frame = np.full((480, 640, 3), 200, np.uint8)
    legend = track_legend(PipelineConfig())
    plain = annotate_frame(frame, [], legend=())
    drawn = annotate_frame(frame, [], legend=legend)
    assert (plain == 200).all()
    changed = np.argwhere((drawn != 200).any(axis=2))
    assert changed[:, 1].max() < 320 and changed[:, 0].min() > 240     # bottom-left quarter
    beside = annotate_frame(frame, [], legend=legend, mask=np.zeros((480, 640), np.uint8),
                            inset="bottom-left")
    right = np.argwhere((beside[:, 200:] != 200).any(axis=2))
    assert right[:, 1].min() + 200 > 320                                 # moved to the right

