"""Figures of a parameter study (matplotlib, Agg backend, imported lazily).

* One parameter → precision–recall curves for the pixel-based, object-based and localized
  object-based framewise metrics (thesis §4.1), side by side, with the line y = x and the points
  labelled by their parameter values (thesis figure 4.4); a label goes where it overlaps no other
  label and no marker, and a point with no such place stays unlabelled (:func:`place_labels`). With several sequences each sequence is a
  thin curve and the average over sequences a thick one; when the sequences belong to several
  groups (sequence types, thesis table 4.1) each group's average is a medium curve.
* Two parameters → precision and recall as heatmaps over the grid (thesis figure 4.11 draws them as
  surfaces; a heatmap with the numbers written in shows the same without hidden faces), averaged
  over sequences; plus the curves of the first parameter, one per value of the second.
  Two parameters also give HOTA over the grid (:func:`metric_heatmaps`): one map per sequence and
  their mean.
* Tracking metrics (HOTA, MOTA, IDF1) against the first parameter.

The best run — the highest HOTA averaged over the sequences (:func:`best_point`) — is marked in
every figure: a star on the curves, an outlined cell in the maps.

Every figure is written as PNG and SVG (atomically).
"""

from __future__ import annotations

import io
import logging
import math
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from ..io.atomic import atomic_write_bytes

log = logging.getLogger(__name__)

__all__ = ["pr_curves", "pr_heatmaps", "metric_heatmaps", "metric_curves", "study_figures",
           "save_figure", "place_labels", "best_point"]

#: the metric whose best run the figures (and the report) mark
BEST_METRIC = "HOTA"
# an explicit colour: the star does not take (and shift) a colour of the curves' cycle
_BEST_STYLE = {"marker": "*", "ms": 16, "mfc": "none", "mec": "crimson", "color": "crimson",
               "mew": 1.6, "ls": "none", "zorder": 5}

_PAIRS = (("pixel", "pixel_precision", "pixel_recall"),
          ("object", "object_area_precision", "object_area_recall"),
          ("localized object", "localized_object_precision", "localized_object_recall"))


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    # fixed salt: SVG clip-path ids (and so the files) are the same on every run
    matplotlib.rcParams["svg.hashsalt"] = "motiontrack"
    # text as <text> elements, not glyph outlines: SVGs several times smaller and searchable
    matplotlib.rcParams["svg.fonttype"] = "none"

    return plt


def _fmt(v: Any) -> str:
    return f"{v:g}" if isinstance(v, (int, float)) and not isinstance(v, bool) else str(v)


def _averaged(over: Sequence[str]) -> str:
    """The title's note of the parameters a figure averages over (none: empty)."""
    return f" (mean over {', '.join(over)})" if over else ""


def save_figure(fig: Any, stem: str | Path) -> list[str]:
    """Write ``stem.png`` (90 dpi) and ``stem.svg`` atomically; close the figure."""
    stem = Path(stem)
    out = []
    for ext, kw in ((".png", {"dpi": 90}), (".svg", {})):
        buf = io.BytesIO()
        # fixed metadata keeps the SVG/PNG bytes reproducible
        meta = {"Date": None} if ext == ".svg" else {"Software": None}
        fig.savefig(buf, format=ext[1:], bbox_inches="tight", metadata=meta, **kw)
        p = stem.with_suffix(ext)
        atomic_write_bytes(p, buf.getvalue())
        out.append(str(p))
    _plt().close(fig)
    return out


def _ordered(values: Sequence[Any]) -> list[Any]:
    """Distinct values in first-seen order."""
    return list(dict.fromkeys(values))


def _mean(vals: Sequence[float]) -> float:
    a = np.asarray(vals, dtype=np.float64)
    a = a[~np.isnan(a)]
    return float(a.mean()) if len(a) else float("nan")


def _curve(rows: Sequence[Mapping[str, Any]], key: str, col: str, values: Sequence[Any]) -> np.ndarray:
    """Mean of ``col`` over the rows with ``key == v`` for each v (nan when none)."""
    return np.array([_mean([float(r[col]) for r in rows if r[key] == v]) for v in values])


def best_point(rows: Sequence[Mapping[str, Any]], keys: Sequence[str],
               metric: str = BEST_METRIC) -> dict[str, Any] | None:
    """The grid point (``{key: value}``) with the highest mean ``metric`` over its sequences;
    the first such point on a tie, None when no row has a defined ``metric``."""
    if not rows or metric not in rows[0]:
        return None
    points = _ordered([tuple(r[k] for k in keys) for r in rows])
    means = [_mean([float(r[metric]) for r in rows if tuple(r[k] for k in keys) == p])
             for p in points]
    if all(math.isnan(m) for m in means):
        return None
    return dict(zip(keys, points[int(np.nanargmax(means))]))


#: where a point's label may go: offset (points) and alignment, nearest first
_LABEL_SPOTS = tuple((dx * s, dy * s, ha, va) for s in (1, 2, 3) for dx, dy, ha, va in (
    (4, 4, "left", "bottom"), (4, -4, "left", "top"), (-4, 4, "right", "bottom"),
    (-4, -4, "right", "top"), (0, 6, "center", "bottom"), (0, -6, "center", "top"),
    (6, 0, "left", "center"), (-6, 0, "right", "center")))


def _obstacles(ax: Any, px_per_pt: float) -> np.ndarray:
    """(N, 4) display-space boxes ``x0, y0, x1, y1`` a label must not cover: every marker of
    the axes and points every few pixels along every line (the curves and y = x)."""
    boxes = []
    for line in ax.get_lines():
        pts = ax.transData.transform(np.column_stack(line.get_data()).astype(float))
        pts = pts[np.isfinite(pts).all(axis=1)]
        if line.get_marker() not in (None, "", "None", " ") and len(pts):
            r = line.get_markersize() * px_per_pt / 2 + 1       # marker radius in pixels
            boxes.append(np.column_stack([pts - r, pts + r]))
        if line.get_linestyle() not in ("None", "none", "", " ") and len(pts) > 1:
            for a, b in zip(pts[:-1], pts[1:]):
                n = max(int(np.hypot(*(b - a)) / 3), 1)
                seg = a + (b - a) * np.linspace(0, 1, n + 1)[:, None]
                boxes.append(np.column_stack([seg - 1, seg + 1]))
    return np.concatenate(boxes) if boxes else np.zeros((0, 4))


def _free(box: tuple[float, float, float, float], others: np.ndarray) -> bool:
    x0, y0, x1, y1 = box
    return not np.any((x0 < others[:, 2]) & (others[:, 0] < x1) & (y0 < others[:, 3])
                      & (others[:, 1] < y1))


def place_labels(ax: Any, xs: Sequence[float], ys: Sequence[float], texts: Sequence[str], *,
                 color: Any, fontsize: float = 7, taken: list | None = None) -> list[Any]:
    """Label the points ``(xs[i], ys[i])`` (data coordinates) with ``texts[i]``, each at the
    first spot of :data:`_LABEL_SPOTS` where it overlaps no label placed before (those in
    ``taken``, a list of display-space boxes ``(x0, y0, x1, y1)`` this call extends), no marker
    and no line of the axes, and does not leave the axes; a point without such a spot stays
    unlabelled. Call it after the axes' limits and aspect are set. Returns the labels placed."""
    from matplotlib.font_manager import FontProperties

    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    ax.apply_aspect()
    px_per_pt = fig.dpi / 72
    taken = [] if taken is None else taken
    obstacles = _obstacles(ax, px_per_pt)
    frame = ax.get_window_extent(renderer)
    font = FontProperties(size=fontsize)
    placed = []
    for (px, py), text in zip(ax.transData.transform(np.column_stack([xs, ys]).astype(float)),
                              texts):
        # the label's box at each spot, from its measured size (cheaper than drawing it there)
        w, h, _ = renderer.get_text_width_height_descent(text, font, ismath=False)
        for dx, dy, ha, va in _LABEL_SPOTS:
            x0 = px + dx * px_per_pt - {"left": 0, "center": w / 2, "right": w}[ha] - 2
            y0 = py + dy * px_per_pt - {"bottom": 0, "center": h / 2, "top": h}[va] - 2
            box = (x0, y0, x0 + w + 4, y0 + h + 4)
            inside = frame.x0 <= x0 and box[2] <= frame.x1 and frame.y0 <= y0 and box[3] <= frame.y1
            if inside and _free(box, obstacles) and _free(box, np.array(taken).reshape(-1, 4)):
                taken.append(box)
                placed.append(ax.annotate(text, ax.transData.inverted().transform((px, py)),
                                          textcoords="offset points", xytext=(dx, dy), ha=ha,
                                          va=va, fontsize=fontsize, color=color))
                break
    return placed


def pr_curves(rows: Sequence[Mapping[str, Any]], key: str, stem: str | Path, *, prefix: str = "det_",
              title: str = "", series: str | None = None,
              best: Mapping[str, Any] | None = None, averaged: Sequence[str] = ()) -> list[str]:
    """Precision–recall curves of the three framewise metric families against parameter ``key``.

    Parameters
    ----------
    rows : table rows (``sequence``, ``key`` and the ``<prefix><metric>`` columns).
    key : the swept parameter (points are labelled with its values).
    stem : output path without extension (``.png`` and ``.svg`` are written).
    prefix : ``"det_"`` (motion regions) or ``"trk_"`` (tracks).
    series : optional second parameter: one curve per value of it instead of per sequence
        (averaged over sequences).
    best : the best grid point (:func:`best_point`), marked with a star on its curve.
    averaged : the study's other parameters, which each point averages over (named in the
        title).

    Returns the written paths.
    """
    plt = _plt()
    values = _ordered([r[key] for r in rows])
    seqs = _ordered([r["sequence"] for r in rows])
    fig, axes = plt.subplots(1, 3, figsize=(15, 5.2))
    for ax, (label, pk, rk) in zip(axes, _PAIRS):
        ax.plot([0, 1], [0, 1], ls="--", color="0.6", lw=1, label="y = x")
        groups: list[tuple[str, list[Mapping[str, Any]], float, bool]] = []
        if series is not None:
            for sv in _ordered([r[series] for r in rows]):
                groups.append((f"{series} = {_fmt(sv)}", [r for r in rows if r[series] == sv], 1.8, True))
        else:
            if len(seqs) > 1:
                for s in seqs:
                    groups.append((s, [r for r in rows if r["sequence"] == s], 1.0, False))
            kinds = _ordered([r.get("group", "") for r in rows])
            if len(kinds) > 1:  # sequence types (thesis table 4.1): one average per type
                for g in kinds:
                    groups.append((f"average {g or '(no group)'}",
                                   [r for r in rows if r.get("group", "") == g], 2.0, False))
            groups.append(("average" if len(seqs) > 1 else seqs[0], list(rows), 3.0, True))
        to_label, star = [], None
        for name, rs, lw, labelled in groups:
            x = _curve(rs, key, prefix + rk, values)
            y = _curve(rs, key, prefix + pk, values)
            ok = ~(np.isnan(x) | np.isnan(y))
            if not ok.any():
                continue
            line, = ax.plot(x[ok], y[ok], marker="o", lw=lw, ms=3 + lw, label=name,
                            alpha=1.0 if labelled else 0.55, zorder=3 if labelled else 2)
            if labelled:
                shown = np.asarray(values, dtype=object)[ok]
                to_label.append((x[ok], y[ok], [_fmt(v) for v in shown], line.get_color()))
                on_curve = best is not None and (series is None or rs[0][series] == best[series])
                if on_curve and best[key] in list(shown):
                    i = list(shown).index(best[key])
                    star = (x[ok][i], y[ok][i])
        if star is not None:   # after the curves: last in the legend
            ax.plot([star[0]], [star[1]], label=f"best {BEST_METRIC}", **_BEST_STYLE)
        ax.set(xlim=(0, 1.02), ylim=(0, 1.02), xlabel="recall", ylabel="precision",
               title=f"{label}-based", aspect="equal")
        ax.grid(True, alpha=0.3)
        legend = ax.legend(fontsize=7, loc="lower left")
        taken = [tuple(legend.get_window_extent(ax.figure.canvas.get_renderer()).extents)]
        for xs, ys, texts, color in reversed(to_label):   # the thick average first: its labels win
            place_labels(ax, xs, ys, texts, color=color, taken=taken)
    what = "motion regions" if prefix == "det_" else "tracks"
    fig.suptitle(title or f"precision–recall of the {what} as {key} varies" + _averaged(averaged))
    return save_figure(fig, stem)


def _outline_best(ax: Any, xs: Sequence[Any], ys: Sequence[Any], best: Mapping[str, Any] | None,
                  key_x: str, key_y: str) -> None:
    """Outline the cell of the best grid point in a map over ``key_x`` × ``key_y``."""
    from matplotlib.patches import Rectangle

    if best is None or best.get(key_x) not in xs or best.get(key_y) not in ys:
        return
    ax.add_patch(Rectangle((xs.index(best[key_x]) - 0.5, ys.index(best[key_y]) - 0.5), 1, 1,
                           fill=False, ec="crimson", lw=2.2, zorder=4,
                           label=f"best {BEST_METRIC}"))


def pr_heatmaps(rows: Sequence[Mapping[str, Any]], key_x: str, key_y: str, stem: str | Path, *,
                prefix: str = "det_", title: str = "",
                best: Mapping[str, Any] | None = None, averaged: Sequence[str] = ()) -> list[str]:
    """Precision (top row) and recall (bottom row) of the three metric families over a 2-D grid
    of ``key_x`` × ``key_y`` (mean over sequences and over the further parameters ``averaged``,
    named in the title), with the numbers written in each cell (thesis figure 4.11); the
    ``best`` grid point outlined. The title names what is scored: the motion regions
    (``det_``) or the tracks (``trk_``)."""
    plt = _plt()
    xs = _ordered([r[key_x] for r in rows])
    ys = _ordered([r[key_y] for r in rows])
    fig, axes = plt.subplots(2, 3, figsize=(4.2 * 3 + 1, 3.2 * 2 + 0.8), squeeze=False)
    for j, (label, pk, rk) in enumerate(_PAIRS):
        for i, (what, col) in enumerate((("precision", pk), ("recall", rk))):
            grid = np.array([[_mean([float(r[prefix + col]) for r in rows
                                     if r[key_x] == xv and r[key_y] == yv]) for xv in xs] for yv in ys])
            _grid_panel(fig, axes[i, j], grid, xs, ys, key_x, key_y, f"{label}-based {what}", best)
    what = "motion regions" if prefix == "det_" else "tracks"
    fig.suptitle(title or f"precision and recall of the {what} over {key_x} × {key_y}"
                 + _averaged(averaged)
                 + (f" (outlined: best {BEST_METRIC})" if best is not None else ""))
    fig.tight_layout()
    return save_figure(fig, stem)


def _grid_panel(fig, ax, grid: np.ndarray, xs: Sequence, ys: Sequence, key_x: str, key_y: str,
                title: str, best: Mapping[str, Any] | None) -> None:
    """One map of values in [0, 1] over the grid ``xs`` × ``ys``: colours, the values written in
    the cells while they stay legible (at most 150), the ``best`` point outlined, a colour bar."""
    im = ax.imshow(grid, origin="lower", cmap="viridis", vmin=0, vmax=1, aspect="auto")
    ax.set_xticks(range(len(xs)), [_fmt(v) for v in xs], fontsize=7, rotation=45)
    ax.set_yticks(range(len(ys)), [_fmt(v) for v in ys], fontsize=7)
    ax.set(xlabel=key_x, ylabel=key_y, title=title)
    if len(xs) * len(ys) <= 150:
        for yi in range(len(ys)):
            for xi in range(len(xs)):
                v = grid[yi, xi]
                if not math.isnan(v):
                    ax.text(xi, yi, f"{v:.2f}", ha="center", va="center", fontsize=6,
                            color="white" if v < 0.6 else "black")
    _outline_best(ax, xs, ys, best, key_x, key_y)
    fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04)


def metric_heatmaps(rows: Sequence[Mapping[str, Any]], key_x: str, key_y: str, stem: str | Path, *,
                    metric: str = BEST_METRIC, best: Mapping[str, Any] | None = None,
                    title: str = "", averaged: Sequence[str] = ()) -> list[str]:
    """``metric`` over the grid ``key_x`` × ``key_y``: one map per sequence and, with several
    sequences, their mean (averaged over the further parameters ``averaged``, named in the
    title), numbers written in the cells and the ``best`` grid point outlined. Returns the
    written paths ([] without ``metric``)."""
    if not rows or metric not in rows[0]:
        return []
    plt = _plt()
    xs = _ordered([r[key_x] for r in rows])
    ys = _ordered([r[key_y] for r in rows])
    seqs = _ordered([r["sequence"] for r in rows])
    panels = [(s, [r for r in rows if r["sequence"] == s]) for s in seqs]
    if len(seqs) > 1:
        panels.append(("mean over sequences", list(rows)))
    cols = min(len(panels), 3)
    nrows = -(-len(panels) // cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.6 * cols + 0.6, 3.6 * nrows + 0.6),
                             squeeze=False)
    for ax in axes.flat[len(panels):]:
        ax.set_axis_off()
    for ax, (name, rs) in zip(axes.flat, panels):
        grid = np.array([[_mean([float(r[metric]) for r in rs if r[key_x] == xv and r[key_y] == yv])
                          for xv in xs] for yv in ys])
        _grid_panel(fig, ax, grid, xs, ys, key_x, key_y, f"{metric}: {name}", best)
    fig.suptitle(title or f"{metric} over {key_x} × {key_y}" + _averaged(averaged)
                 + (f" (outlined: best mean {BEST_METRIC})" if best is not None else ""))
    fig.tight_layout()
    return save_figure(fig, stem)


def metric_curves(rows: Sequence[Mapping[str, Any]], key: str, stem: str | Path,
                  metrics: Sequence[str] = ("HOTA", "MOTA", "IDF1"), title: str = "",
                  best: Mapping[str, Any] | None = None, averaged: Sequence[str] = ()
                  ) -> list[str]:
    """Tracking metrics against ``key``: thin per-sequence lines, thick average; the ``best``
    grid point's value of ``key`` starred on every average curve. Each point is the mean over
    the study's other parameters ``averaged``, named in the title."""
    plt = _plt()
    values = _ordered([r[key] for r in rows])
    seqs = _ordered([r["sequence"] for r in rows])
    numeric = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)
    xpos = np.asarray(values, dtype=float) if numeric else np.arange(len(values), dtype=float)
    metrics = [m for m in metrics if rows and m in rows[0]]
    fig, axes = plt.subplots(1, max(len(metrics), 1), figsize=(4.5 * max(len(metrics), 1), 3.8),
                             squeeze=False)
    for ax, m in zip(axes[0], metrics):
        if len(seqs) > 1:
            for s in seqs:
                ax.plot(xpos, _curve([r for r in rows if r["sequence"] == s], key, m, values),
                        lw=1, alpha=0.55, marker=".", label=s)
        mean = _curve(rows, key, m, values)
        ax.plot(xpos, mean, lw=3, marker="o", label="average" if len(seqs) > 1 else seqs[0])
        if best is not None and best.get(key) in values:
            i = values.index(best[key])
            ax.plot([xpos[i]], [mean[i]], label=f"best {BEST_METRIC}: {key} = {_fmt(best[key])}",
                    **_BEST_STYLE)
        if not numeric:
            ax.set_xticks(xpos, [_fmt(v) for v in values])
        ax.set(xlabel=key, ylabel=m, title=m)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(title or f"tracking metrics as {key} varies" + _averaged(averaged))
    fig.tight_layout()
    return save_figure(fig, stem)


def study_figures(rows: Sequence[Mapping[str, Any]], study: Any, out_dir: str | Path) -> list[str]:
    """All figures of a study (see the module doc); returns the written paths."""
    out = Path(out_dir)
    keys = list(study.keys)
    if not rows:
        return []
    paths: list[str] = []
    k1 = keys[0]
    best = best_point(rows, keys)
    if len(keys) == 1:
        paths += pr_curves(rows, k1, out / "pr_regions", prefix="det_", best=best)
        paths += pr_curves(rows, k1, out / "pr_tracks", prefix="trk_", best=best)
    else:
        k2 = keys[1]
        # with more than two parameters the maps average over the others: the best point is
        # marked only where it is one cell
        best2 = best if len(keys) == 2 else None
        rest = keys[2:]
        paths += pr_heatmaps(rows, k1, k2, out / "pr_map_regions", prefix="det_", best=best2,
                             averaged=rest)
        paths += pr_curves(rows, k1, out / "pr_regions", prefix="det_", series=k2, best=best2,
                           averaged=rest)
        paths += pr_heatmaps(rows, k1, k2, out / "pr_map_tracks", prefix="trk_", best=best2,
                             averaged=rest)
        paths += metric_heatmaps(rows, k1, k2, out / "hota_map", best=best2, averaged=rest)
    paths += metric_curves(rows, k1, out / "tracking", best=best if len(keys) == 1 else None,
                           averaged=keys[1:])
    return paths
