"""Figures of a parameter study (matplotlib, Agg backend, imported lazily).

* One parameter → precision–recall curves for the pixel-based, object-based and localized
  object-based framewise metrics (thesis §4.1), side by side, with the line y = x and every point
  labelled by its parameter value (thesis figure 4.4). With several sequences each sequence is a
  thin curve and the average over sequences a thick one; when the sequences belong to several
  groups (sequence types, thesis table 4.1) each group's average is a medium curve.
* Two parameters → precision and recall as heatmaps over the grid (thesis figure 4.11 draws them as
  surfaces; a heatmap with the numbers written in shows the same without hidden faces), averaged
  over sequences; plus the curves of the first parameter, one per value of the second.
* Tracking metrics (HOTA, MOTA, IDF1) against the first parameter.

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

__all__ = ["pr_curves", "pr_heatmaps", "metric_curves", "study_figures", "save_figure"]

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


def pr_curves(rows: Sequence[Mapping[str, Any]], key: str, stem: str | Path, *, prefix: str = "det_",
              title: str = "", series: str | None = None) -> list[str]:
    """Precision–recall curves of the three framewise metric families against parameter ``key``.

    Parameters
    ----------
    rows : table rows (``sequence``, ``key`` and the ``<prefix><metric>`` columns).
    key : the swept parameter (points are labelled with its values).
    stem : output path without extension (``.png`` and ``.svg`` are written).
    prefix : ``"det_"`` (motion regions) or ``"trk_"`` (tracks).
    series : optional second parameter: one curve per value of it instead of per sequence
        (averaged over sequences).

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
        for name, rs, lw, labelled in groups:
            x = _curve(rs, key, prefix + rk, values)
            y = _curve(rs, key, prefix + pk, values)
            ok = ~(np.isnan(x) | np.isnan(y))
            if not ok.any():
                continue
            line, = ax.plot(x[ok], y[ok], marker="o", lw=lw, ms=3 + lw, label=name,
                            alpha=1.0 if labelled else 0.55, zorder=3 if labelled else 2)
            if labelled:
                for v, xi, yi in zip(np.asarray(values, dtype=object)[ok], x[ok], y[ok]):
                    ax.annotate(_fmt(v), (xi, yi), textcoords="offset points", xytext=(4, 4),
                                fontsize=7, color=line.get_color())
        ax.set(xlim=(0, 1.02), ylim=(0, 1.02), xlabel="recall", ylabel="precision",
               title=f"{label}-based", aspect="equal")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="lower left")
    what = "motion regions" if prefix == "det_" else "tracks"
    fig.suptitle(title or f"precision–recall of the {what} as {key} varies")
    return save_figure(fig, stem)


def pr_heatmaps(rows: Sequence[Mapping[str, Any]], key_x: str, key_y: str, stem: str | Path, *,
                prefix: str = "det_", title: str = "") -> list[str]:
    """Precision (top row) and recall (bottom row) of the three metric families over a 2-D grid
    of ``key_x`` × ``key_y`` (mean over sequences and over any further parameters), with the
    numbers written in each cell (thesis figure 4.11)."""
    plt = _plt()
    xs = _ordered([r[key_x] for r in rows])
    ys = _ordered([r[key_y] for r in rows])
    fig, axes = plt.subplots(2, 3, figsize=(4.2 * 3 + 1, 3.2 * 2 + 0.8), squeeze=False)
    for j, (label, pk, rk) in enumerate(_PAIRS):
        for i, (what, col) in enumerate((("precision", pk), ("recall", rk))):
            grid = np.array([[_mean([float(r[prefix + col]) for r in rows
                                     if r[key_x] == xv and r[key_y] == yv]) for xv in xs] for yv in ys])
            ax = axes[i, j]
            im = ax.imshow(grid, origin="lower", cmap="viridis", vmin=0, vmax=1, aspect="auto")
            ax.set_xticks(range(len(xs)), [_fmt(v) for v in xs], fontsize=7, rotation=45)
            ax.set_yticks(range(len(ys)), [_fmt(v) for v in ys], fontsize=7)
            ax.set(xlabel=key_x, ylabel=key_y, title=f"{label}-based {what}")
            if len(xs) * len(ys) <= 150:
                for yi in range(len(ys)):
                    for xi in range(len(xs)):
                        v = grid[yi, xi]
                        if not math.isnan(v):
                            ax.text(xi, yi, f"{v:.2f}", ha="center", va="center", fontsize=6,
                                    color="white" if v < 0.6 else "black")
            fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04)
    fig.suptitle(title or f"precision and recall over {key_x} × {key_y}")
    fig.tight_layout()
    return save_figure(fig, stem)


def metric_curves(rows: Sequence[Mapping[str, Any]], key: str, stem: str | Path,
                  metrics: Sequence[str] = ("HOTA", "MOTA", "IDF1"), title: str = "") -> list[str]:
    """Tracking metrics against ``key``: thin per-sequence lines, thick average."""
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
        ax.plot(xpos, _curve(rows, key, m, values), lw=3, marker="o",
                label="average" if len(seqs) > 1 else seqs[0])
        if not numeric:
            ax.set_xticks(xpos, [_fmt(v) for v in values])
        ax.set(xlabel=key, ylabel=m, title=m)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(title or f"tracking metrics as {key} varies")
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
    if len(keys) == 1:
        paths += pr_curves(rows, k1, out / "pr_regions", prefix="det_")
        paths += pr_curves(rows, k1, out / "pr_tracks", prefix="trk_")
    else:
        k2 = keys[1]
        paths += pr_heatmaps(rows, k1, k2, out / "pr_map_regions", prefix="det_")
        paths += pr_curves(rows, k1, out / "pr_regions", prefix="det_", series=k2)
        paths += pr_heatmaps(rows, k1, k2, out / "pr_map_tracks", prefix="trk_")
    paths += metric_curves(rows, k1, out / "tracking")
    return paths
