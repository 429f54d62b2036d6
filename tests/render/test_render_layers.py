"""Layers of the annotated frame that do not change from frame to frame are drawn once per frame
size: the legend panel and the zones' tint (render/annotate.py, render/scene.py)."""

from __future__ import annotations

import tracemalloc
from types import SimpleNamespace

import cv2
import numpy as np

from motiontrack.render import annotate
from motiontrack.render import scene as scene_module
from motiontrack.render.annotate import annotate_frame, draw_legend
from motiontrack.render.scene import ZONE_COLOR, draw_scene

ENTRIES = (("track", "track (id, trail)"), ("predicted", "track, not seen"),
           ("region", "motion region"), ("hypothesis", "shape hypothesis"), ("head", "head"),
           ("points", "feature points"))


def _scene(h=576, w=768, seed=0):
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.integers(0, 255, (h, w, 3), dtype=np.uint8), (5, 5), 0)


def _legend_drawn_on_the_frame(img, entries, origin):
    """The legend drawn directly on the frame: the scene under the panel darkened to 2/5, then
    the symbols and labels."""
    scale, thick = annotate.text_scale(img.shape)
    scale *= 0.8
    font = cv2.FONT_HERSHEY_SIMPLEX
    (_, th), base = cv2.getTextSize("Ag", font, scale, thick)
    row, size, pad = th + base + max(2, th // 3), th + base // 2, max(3, th // 3)
    width = max(cv2.getTextSize(label, font, scale, thick)[0][0] for _, label in entries)
    pw, ph = pad * 3 + size + width, pad * 2 + row * len(entries) - (row - size)
    x0, y0 = origin[0], origin[1] - ph
    img[y0:y0 + ph, x0:x0 + pw] = (img[y0:y0 + ph, x0:x0 + pw].astype(np.uint16) * 2 // 5)
    for i, (style, label) in enumerate(entries):
        y = y0 + pad + i * row
        annotate._swatch(img, style, x0 + pad, y, size, img.shape)
        cv2.putText(img, label, (x0 + 2 * pad + size, y + size - base // 2), font, scale,
                    (255, 255, 255), thick, cv2.LINE_AA)
    return ph


def test_the_legend_panel_drawn_once_looks_as_if_drawn_on_each_frame():
    for seed in (0, 1):                       # the second frame reuses the panel of the first
        scene = _scene(seed=seed)
        expected, got = scene.copy(), scene.copy()
        h_expected = _legend_drawn_on_the_frame(expected, ENTRIES, (6, 560))
        assert draw_legend(got, ENTRIES, (6, 560)) == h_expected
        diff = np.abs(expected.astype(int) - got.astype(int))
        assert diff.max() <= 2                # rounding of the darkening and of anti-aliasing
        changed = (scene != got).any(axis=2)
        assert np.array_equal(changed, (scene != expected).any(axis=2) | changed)
        rows, cols = np.nonzero(changed)
        assert rows.max() < 560 and cols.min() >= 6     # bottom-left corner at the origin


def test_the_legend_fits_each_frame_size_it_meets():
    small, large = _scene(240, 320), _scene(1080, 1920)
    h_small = draw_legend(small.copy(), ENTRIES[:2], (4, 236))
    h_large = draw_legend(large.copy(), ENTRIES[:2], (4, 1076))
    assert h_large > 3 * h_small              # text sized by the frame, not by the first frame
    again = small.copy()
    assert draw_legend(again, ENTRIES[:2], (4, 236)) == h_small


def test_a_legend_on_a_gray_frame_darkens_and_labels_it():
    gray = np.full((240, 320), 200, np.uint8)
    h = draw_legend(gray, ENTRIES[:2], (4, 236))
    panel = gray[236 - h:236, 4:]
    assert (panel == 80).any() and panel.max() > 200     # 200 * 2/5, and white text


def _zones():
    return [SimpleNamespace(name="pen", polygon=[[100.4, 300], [400, 300], [400, 500], [100, 500]]),
            SimpleNamespace(name="gate", polygon=[[500, 100], [700, 120], [650, 300]]),
            SimpleNamespace(name="corner", polygon=[[-50, -20], [60, 10], [30, 90]])]


def test_the_zone_tint_is_a_tinted_copy_of_the_frame_blended_in():
    zones = _zones()
    polygons = [np.round(np.asarray(z.polygon)).astype(np.int32) for z in zones]
    for seed in (0, 1):                       # the second frame reuses the zones' layer
        scene = _scene(seed=seed)
        tinted = scene.copy()
        cv2.fillPoly(tinted, polygons, ZONE_COLOR)
        expected = cv2.addWeighted(tinted, 0.15, scene, 0.85, 0.0)
        got = scene.copy()
        scene_module._tint_zones(got, tuple(tuple(map(tuple, p.tolist())) for p in polygons))
        assert np.array_equal(got, expected)
        drawn = scene.copy()                  # and draw_scene tints no pixel outside the zones
        draw_scene(drawn, [], zones, None)
        mask = np.zeros(scene.shape[:2], np.uint8)
        cv2.fillPoly(mask, polygons, 255)
        far = cv2.dilate(mask, np.ones((41, 41), np.uint8)) == 0   # beyond outlines and labels
        assert np.array_equal(drawn[far], scene[far])


def test_the_zone_tint_allocates_no_frame_sized_image():
    img = _scene(1080, 1920)
    zones = [SimpleNamespace(name="z", polygon=[[100, 100], [300, 100], [300, 250]])]
    draw_scene(img, [], zones, None)          # the zone layer is made at the first frame
    tracemalloc.start()
    try:
        draw_scene(img, [], zones, None)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < img.nbytes // 10


def test_annotating_a_frame_leaves_the_frame_untouched():
    frame = _scene()
    before = frame.copy()
    annotate_frame(frame, [], legend=ENTRIES[:2], text="frame 3")
    assert np.array_equal(frame, before)


def test_the_legend_is_drawn_once_per_frame_size(monkeypatch):
    calls = []
    real = cv2.putText
    monkeypatch.setattr(annotate.cv2, "putText", lambda *a, **k: (calls.append(1), real(*a, **k)))
    entries = (("track", "drawn once"), ("region", "per frame size"))
    for _ in range(5):
        draw_legend(_scene(300, 400), entries, (4, 296))
    assert len(calls) == 2 * len(entries)     # over black and over white, at the first frame
