"""Figures of a study drawn from hand-built tables: labels that do not overlap, the best run
marked, HOTA maps of a two-parameter study."""

from __future__ import annotations

import itertools
import math
from types import SimpleNamespace

import pytest

pytest.importorskip("matplotlib")

from motiontrack.studies import plots  # noqa: E402


def _row(run, seq, params, p, r, hota):
    """One table row whose three precision/recall pairs (regions and tracks) are (p, r)."""
    row = {"run": run, "sequence": seq, "group": "", **params, "HOTA": hota, "MOTA": hota - 0.1,
           "IDF1": hota + 0.1}
    for prefix in ("det_", "trk_"):
        for _, pk, rk in plots._PAIRS:
            row[prefix + pk], row[prefix + rk] = p, r
    return row


def _crowded_rows():
    """30 thresholds whose PR points lie a few thousandths apart: every label at one fixed
    offset would overlap its neighbours; HOTA peaks at the 12th value."""
    rows = []
    for i in range(30):
        t = round(0.01 * (i + 1), 2)
        rows.append(_row(i + 1, "walker", {"thr": t}, 0.5 + 0.004 * i, 0.9 - 0.003 * i,
                         0.6 - abs(i - 11) * 0.01))
    return rows


@pytest.fixture
def captured(monkeypatch):
    """The figures ``plots`` draws, kept open instead of written."""
    figs = []
    monkeypatch.setattr(plots, "save_figure", lambda fig, stem: figs.append(fig) or [str(stem)])
    yield figs
    for fig in figs:
        plots._plt().close(fig)


def _label_boxes(fig):
    """Display-space boxes of the point labels (the annotations) of every axes, per axes."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    return [[t.get_window_extent(renderer) for t in ax.texts] for ax in fig.axes]


def test_point_labels_of_pr_curves_do_not_overlap(captured):
    rows = _crowded_rows()
    plots.pr_curves(rows, "thr", "pr", best=plots.best_point(rows, ["thr"]))
    fig = captured[0]
    boxes = _label_boxes(fig)
    assert all(len(b) >= 5 for b in boxes)        # labelled, just not every crowded point
    for ax, axis_boxes in zip(fig.axes, boxes):
        for a, b in itertools.combinations(axis_boxes, 2):
            assert not a.overlaps(b), (a, b)
        # nor on a point of a curve
        points = [ax.transData.transform(xy) for line in ax.get_lines() if line.get_marker() == "o"
                  for xy in line.get_xydata()]
        assert not any(box.contains(*p) for box in axis_boxes for p in points)


def test_labels_of_a_sparse_curve_are_all_placed(captured):
    rows = [_row(i, "walker", {"thr": t}, 0.2 + 0.15 * i, 0.95 - 0.15 * i, 0.5)
            for i, t in enumerate((0.05, 0.1, 0.15, 0.2, 0.25), start=1)]
    plots.pr_curves(rows, "thr", "pr")
    texts = [[t.get_text() for t in ax.texts] for ax in captured[0].axes]
    assert all(sorted(t) == ["0.05", "0.1", "0.15", "0.2", "0.25"] for t in texts)


def test_best_point_is_the_highest_mean_hota_over_sequences():
    rows = [_row(1, "a", {"thr": 0.1}, .5, .5, 0.9), _row(1, "b", {"thr": 0.1}, .5, .5, 0.1),
            _row(2, "a", {"thr": 0.2}, .5, .5, 0.6), _row(2, "b", {"thr": 0.2}, .5, .5, 0.6),
            _row(3, "a", {"thr": 0.3}, .5, .5, math.nan), _row(3, "b", {"thr": 0.3}, .5, .5, 0.7)]
    # means 0.5, 0.6 and 0.7 (nan left out of the mean)
    assert plots.best_point(rows, ["thr"]) == {"thr": 0.3}
    assert plots.best_point([{k: v for k, v in r.items() if k != "HOTA"} for r in rows],
                            ["thr"]) is None


def test_best_run_is_starred_on_the_curves(captured):
    rows = _crowded_rows()
    best = plots.best_point(rows, ["thr"])
    assert best == {"thr": 0.12}
    plots.pr_curves(rows, "thr", "pr", best=best)
    plots.metric_curves(rows, "thr", "tracking", best=best)
    pr, tracking = captured
    for ax in pr.axes:
        stars = [ln for ln in ax.get_lines() if ln.get_marker() == "*"]
        assert len(stars) == 1
        assert tuple(stars[0].get_xydata()[0]) == pytest.approx((0.9 - 0.003 * 11, 0.5 + 0.004 * 11))
    for ax in tracking.axes:
        stars = [ln for ln in ax.get_lines() if ln.get_marker() == "*"]
        assert len(stars) == 1 and stars[0].get_xydata()[0][0] == pytest.approx(0.12)
        assert "best HOTA: thr = 0.12" in [t.get_text() for t in ax.get_legend().get_texts()]


def test_two_parameter_study_gets_hota_maps_per_sequence_and_mean(captured, tmp_path):
    rows = []
    for run, (t, m) in enumerate(itertools.product((0.1, 0.2, 0.3), (0, 0.001)), start=1):
        for seq, bonus in (("walker", 0.0), ("crossing", 0.2)):
            hota = 0.3 + bonus + (0.3 if (t, m) == (0.2, 0.001) else 0.0)
            rows.append(_row(run, seq, {"thr": t, "min": m}, 0.5, 0.5, hota))
    study = SimpleNamespace(keys=("thr", "min"))
    written = plots.study_figures(rows, study, tmp_path)
    assert str(tmp_path / "hota_map") in written
    hota_map = captured[[str(tmp_path / "hota_map") == w for w in written].index(True)]
    panels = [ax for ax in hota_map.axes if ax.get_title().startswith("HOTA")]
    assert [ax.get_title() for ax in panels] == ["HOTA: walker", "HOTA: crossing",
                                                 "HOTA: mean over sequences"]
    mean = panels[2].images[0].get_array()
    assert mean[1, 1] == pytest.approx(0.7) and mean[0, 0] == pytest.approx(0.4)  # rows = min
    for ax in panels:                     # the best cell, thr 0.2 (x 1) x min 0.001 (y 1)
        (outline,) = ax.patches
        assert outline.get_xy() == (0.5, 0.5)


def test_one_parameter_study_draws_no_maps(captured, tmp_path):
    written = plots.study_figures(_crowded_rows(), SimpleNamespace(keys=("thr",)), tmp_path)
    assert not any("map" in w for w in written)


def test_the_star_takes_no_colour_of_the_curves(captured):
    from matplotlib.colors import to_hex

    rows = [_row(run, "walker", {"thr": t, "min": m}, 0.3 + t, 0.9 - t, 0.5 + t * (m == 0.001))
            for run, (t, m) in enumerate(itertools.product((0.1, 0.2, 0.3), (0, 0.001, 0.002)), 1)]
    plots.pr_curves(rows, "thr", "pr", series="min", best=plots.best_point(rows, ["thr", "min"]))
    ax = captured[0].axes[0]
    curves = [to_hex(ln.get_color()) for ln in ax.get_lines() if ln.get_marker() == "o"]
    assert curves == ["#1f77b4", "#ff7f0e", "#2ca02c"]       # C0, C1, C2: the cycle in order
    assert [t.get_text() for t in ax.get_legend().get_texts()][-1] == "best HOTA"


def _titles(captured, written, tmp_path):
    """Figure name → its title (suptitle)."""
    return {str(w)[len(str(tmp_path)) + 1:]: fig._suptitle.get_text()
            for w, fig in zip(written, captured)}


@pytest.mark.parametrize("keys, averaged", [
    (("thr", "min"), {"tracking": "(mean over min)"}),
    (("thr", "min", "k"), {"tracking": "(mean over min, k)", "hota_map": "(mean over k)",
                           "pr_map_regions": "(mean over k)", "pr_map_tracks": "(mean over k)",
                           "pr_regions": "(mean over k)"}),
])
def test_every_figure_has_its_own_title_and_names_the_parameters_it_averages_over(
        captured, tmp_path, keys, averaged):
    rows = []
    third = (3, 4) if len(keys) == 3 else (None,)
    for run, point in enumerate(itertools.product((0.1, 0.2), (0, 1), third), start=1):
        rows.append(_row(run, "walker", dict(zip(keys, point)), 0.5, 0.5, 0.3 + 0.1 * run))
    written = plots.study_figures(rows, SimpleNamespace(keys=keys), tmp_path)
    titles = _titles(captured, written, tmp_path)
    assert len(set(titles.values())) == len(titles)          # no two figures share a title
    assert "motion regions" in titles["pr_map_regions"] and "tracks" in titles["pr_map_tracks"]
    for name, title in titles.items():
        assert (averaged[name] in title) if name in averaged else "mean over" not in title, name


def test_a_one_parameter_study_averages_over_nothing_and_says_nothing(captured, tmp_path):
    written = plots.study_figures(_crowded_rows(), SimpleNamespace(keys=("thr",)), tmp_path)
    assert not any("mean over" in t for t in _titles(captured, written, tmp_path).values())
