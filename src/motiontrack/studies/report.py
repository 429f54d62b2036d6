"""One self-contained HTML page per study (``motiontrack report DIR -o report.html``).

The page opens with the key metrics (HOTA, MOTA, IDF1: the best run by mean HOTA and the best of
each metric), before any figure or long table; the best run is marked in both tables as in the
figures. It then holds the evaluation meta data (base tracker parameters, the swept grid, sequences and
their ground truth, evaluation parameters, software versions), the per-run summary table and the
full run × sequence table, every figure of ``DIR/figures`` (an ``<img>`` with the SVG, or the PNG
when no SVG exists, as a base64 ``data:`` URL) and relative links to the annotated clips /
intermediate videos found under ``DIR``. The base parameters listed are those of the stages
that ran at some point of the grid (:func:`~motiontrack.config_activity.inactive_in_study`): no
``people.*`` with the people stage off, no ``motion.mog2.*`` while ``motion.method = knn``. It
has no scripts and no external resources (fonts, style
sheets), so it reads offline in any browser; nothing read from ``DIR`` becomes markup: text is
escaped, figures are images (an SVG shown as an image runs no scripts) and links are
percent-encoded relative paths.
"""

from __future__ import annotations

import base64
import html
import logging
import math
import os
import urllib.parse
from pathlib import Path
from typing import Any, Mapping, Sequence

from ..config_activity import inactive_in_study
from ..errors import ConfigError, printable
from ..io.atomic import atomic_write_text
from .plots import BEST_METRIC, best_point
from .study_file import read_study_meta
from .sweep import SUMMARY_FILE, TABLE_FILE
from .table import read_table

log = logging.getLogger(__name__)

__all__ = ["build_report", "write_report"]

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:2em auto;
max-width:1200px;padding:0 1em;color:#222}
h1{font-size:1.6em}h2{border-bottom:1px solid #ddd;padding-bottom:.2em;margin-top:2em}
table{border-collapse:collapse;font-size:.82em;margin:.5em 0}
th,td{border:1px solid #ccc;padding:.2em .45em;text-align:right}
th{background:#f3f3f3;position:sticky;top:0}td.t{text-align:left}
.scroll{overflow:auto;max-height:32em;border:1px solid #eee}
figure{margin:1em 0}figure svg,figure img{max-width:100%;height:auto}
code,pre{background:#f6f6f6;padding:.1em .3em}pre{padding:.6em;overflow:auto}
.small{color:#666;font-size:.85em}
tr.best td{background:#fdecea;font-weight:600}
tr.swept th,tr.swept td{background:#eef4fb;font-weight:600}
#key-metrics td,#key-metrics th{font-size:1.15em}
"""

#: the metrics of the block at the top of the page
KEY_METRICS = ("HOTA", "MOTA", "IDF1")

#: marks the best run's rows in the tables (the figures star it)
BEST_MARK = "\u2605"

#: columns shown in the per-run summary table (when present)
SUMMARY_COLUMNS = ("det_pixel_precision", "det_pixel_recall", "det_object_area_precision",
                   "det_object_area_recall", "det_localized_object_precision",
                   "det_localized_object_recall", "HOTA", "MOTA", "IDF1", "IDSW")


def _e(x: Any) -> str:
    return html.escape(str(x), quote=True)


def _cell(v: Any) -> str:
    if isinstance(v, float):
        return "nan" if math.isnan(v) else f"{v:.4g}"
    return _e(v)


def _table(rows: Sequence[Mapping[str, Any]], cols: Sequence[str], text_cols: Sequence[str] = (),
           best_run: Any = None) -> str:
    """A scrolling table; the rows of run ``best_run`` get class ``best`` and a star."""
    head = "".join(f"<th>{_e(c)}</th>" for c in cols)
    body = []
    for r in rows:
        best = best_run is not None and r.get("run") == best_run
        cells = []
        for c in cols:
            text = _cell(r.get(c, ""))
            if best and c == "run":
                text = f"{BEST_MARK} {text}"
            cells.append(f"<td class=\"t\">{text}</td>" if c in text_cols else f"<td>{text}</td>")
        body.append(("<tr class=\"best\">" if best else "<tr>") + "".join(cells) + "</tr>")
    return (f"<div class=\"scroll\"><table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}"
            "</tbody></table></div>")


def _number(v: Any) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")


def _best_run(rows: Sequence[Mapping[str, Any]], keys: Sequence[str]) -> Any:
    """The run of the grid point with the highest mean HOTA over the sequences (the one the
    figures star), or None."""
    point = best_point([{**r, BEST_METRIC: _number(r.get(BEST_METRIC))} for r in rows], keys) \
        if rows and BEST_METRIC in rows[0] else None
    if point is None:
        return None
    return next(r["run"] for r in rows if all(r.get(k) == v for k, v in point.items()))


def _key_metrics(per_run: Sequence[Mapping[str, Any]], keys: Sequence[str], best_run: Any) -> str:
    """The block at the top: the best run (by mean HOTA) with its settings and key metrics, and
    for each key metric the run that has its best value."""
    metrics = [m for m in KEY_METRICS if per_run and m in per_run[0]]
    if not metrics:
        return "<p>No tracking metrics in this study (no ground truth).</p>"
    lines = []
    for label, metric in ((f"best run (mean {BEST_METRIC})", None), *((f"best {m}", m) for m in metrics)):
        if metric is None:
            run = best_run
        else:
            scored = [(v, i) for i, r in enumerate(per_run) if not math.isnan(v := _number(r.get(metric)))]
            run = per_run[max(scored, key=lambda s: (s[0], -s[1]))[1]]["run"] if scored else None
        row = next((r for r in per_run if r.get("run") == run), None)
        if row is None:
            continue
        cells = "".join(f"<td>{_cell(row.get(k, ''))}</td>" for k in keys)
        cells += "".join(f"<td>{_cell(_number(row.get(m)))}</td>" for m in metrics)
        is_best = run == best_run
        lines.append(("<tr class=\"best\">" if is_best else "<tr>") + f"<th>{_e(label)}</th>"
                     f"<td>{BEST_MARK + ' ' if is_best else ''}{_cell(run)}</td>{cells}</tr>")
    head = "".join(f"<th>{_e(c)}</th>" for c in ["", "run", *keys, *metrics])
    return (f"<table id=\"key-metrics-table\"><thead><tr>{head}</tr></thead><tbody>{''.join(lines)}"
            "</tbody></table>")


def _active_parameters(meta: Mapping[str, Any]) -> tuple[dict[str, Any], int]:
    """The base parameters that take effect at some grid point, and how many were left out.
    A key this version does not know (a study from another version) is kept."""
    base = meta.get("base_config", {})
    flat = _flat(base)
    domains = {g["key"]: list(g["values"]) for g in meta.get("grid", [])}
    shown = {}
    for key, value in flat.items():
        try:
            dead = inactive_in_study(base, [key], domains)
        except (ConfigError, TypeError, ValueError, KeyError):
            dead = []
        if not dead:
            shown[key] = value
    return shown, len(flat) - len(shown)


def _value(v: Any) -> str:
    """A parameter value as written in a config: a whole float without its ``.0`` (300, not
    300.0), other floats in full (``repr``), anything else as text."""
    if isinstance(v, float) and math.isfinite(v) and v == int(v) and abs(v) < 1e15:
        return str(int(v))
    return repr(v) if isinstance(v, float) else str(v)


def _kv(d: Mapping[str, Any]) -> str:
    return "<table>" + "".join(f"<tr><th>{_e(k)}</th><td class=\"t\">{_e(_value(v))}</td></tr>"
                               for k, v in d.items()) + "</table>"


def _base_table(params: Mapping[str, Any], domains: Mapping[str, Sequence[Any]]) -> str:
    """The base parameters; a swept key's row is marked (class ``swept``) and gives the values
    the runs took, its base value being in effect in none of them."""
    rows = []
    for k, v in params.items():
        if k in domains:
            swept = ", ".join(_value(x) for x in domains[k])
            rows.append(f"<tr class=\"swept\"><th>{_e(k)}</th><td class=\"t\">swept: "
                        f"{_e(swept)} <span class=\"small\">(base {_e(_value(v))}, used by no "
                        "run)</span></td></tr>")
        else:
            rows.append(f"<tr><th>{_e(k)}</th><td class=\"t\">{_e(_value(v))}</td></tr>")
    return "<table id=\"base-parameters\">" + "".join(rows) + "</table>"


def _flat(d: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in d.items():
        if isinstance(v, Mapping):
            out.update(_flat(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


#: figure types embedded, in order of preference: suffix → media type
FIGURE_TYPES = {".svg": "image/svg+xml", ".png": "image/png"}


def _figure_bytes(path: Path, root: Path) -> bytes | None:
    """The content of a figure file inside the study folder ``root``, or None (logged) for one
    that lies outside it (a symbolic link) or cannot be read."""
    try:
        real = path.resolve()
        if not real.is_relative_to(root):
            log.warning("figure %s lies outside the study folder: left out", printable(path))
            return None
        return real.read_bytes()
    except OSError as exc:
        log.warning("cannot read figure %s (%s): left out", printable(path),
                    printable(exc.strerror or exc))
        return None


def _figures(folder: Path) -> str:
    """Every figure of ``folder/figures`` as an ``<img>`` with a ``data:`` URL (SVG preferred).

    An SVG shown as an image runs no scripts and loads nothing, whatever it contains, so a study
    folder from someone else cannot run code in the reader's browser; inlining the SVG markup
    would.
    """
    fig_dir = folder / "figures"
    if not fig_dir.is_dir():
        return "<p>No figures.</p>"
    root = folder.resolve()
    found: dict[str, dict[str, Path]] = {}
    for p in fig_dir.iterdir():
        if p.suffix in FIGURE_TYPES and p.is_file():
            found.setdefault(p.stem, {})[p.suffix] = p
    parts = []
    for stem in sorted(found):
        for suffix, media in FIGURE_TYPES.items():
            data = _figure_bytes(found[stem][suffix], root) if suffix in found[stem] else None
            if data is not None:
                b64 = base64.b64encode(data).decode("ascii")
                parts.append(f"<figure><img alt=\"{_e(stem)}\" src=\"data:{media};base64,{b64}\">"
                             f"<figcaption>{_e(stem)}</figcaption></figure>")
                break
    return "\n".join(parts) or "<p>No figures.</p>"


def _clips(folder: Path, report_dir: Path) -> str:
    vids = sorted(p for ext in ("*.webm", "*.mp4", "*.avi") for p in folder.rglob(ext)
                  if not p.name.startswith("."))
    if not vids:
        return "<p>No clips (run the sweep with <code>--save annotated,background,difference,motion</code>).</p>"
    items = []
    for v in vids:
        rel = os.path.relpath(v, report_dir).replace(os.sep, "/")
        # percent-encoded, so that a file name such as "javascript:x.webm" stays a relative
        # link rather than becoming a URL scheme, and "#" or "?" in a name stay part of it
        href = urllib.parse.quote(rel)
        items.append(f"<li><a href=\"{_e(href)}\">{_e(v.relative_to(folder).as_posix())}</a></li>")
    return "<ul>" + "".join(items) + "</ul>"


def build_report(folder: str | Path, report_path: str | Path | None = None) -> str:
    """The HTML text of the report of the study in ``folder`` (links relative to ``report_path``)."""
    folder = Path(folder)
    meta = read_study_meta(folder)  # InputError for a missing or malformed study.json
    rows = read_table(folder / TABLE_FILE, required=("run", "sequence"))
    summary = (read_table(folder / SUMMARY_FILE, required=("run",))
               if (folder / SUMMARY_FILE).is_file() else [])
    keys = [g["key"] for g in meta.get("grid", [])]
    report_dir = Path(report_path).resolve().parent if report_path else folder.resolve()
    seqs = meta.get("sequences", [])
    grid_rows = [{"parameter": g["key"], "values": ", ".join(map(_value, g["values"]))}
                 for g in meta.get("grid", [])]
    ev = dict(meta.get("evaluation", {}))
    sum_cols = ["run"] + keys + [c for c in SUMMARY_COLUMNS if summary and c in summary[0]]
    all_cols = list(rows[0].keys()) if rows else []
    best_run = _best_run(rows, keys)
    params, left_out = _active_parameters(meta)
    title = f"Parameter study: {', '.join(keys)}"
    out = [
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">",
        f"<title>{_e(title)}</title><style>{_CSS}</style></head><body>",
        f"<h1>{_e(title)}</h1>",
        f"<p class=\"small\">{len(summary) or meta.get('runs', '?')} parameter settings × "
        f"{len(seqs)} sequence(s); study folder <code>{_e(folder.resolve())}</code>. "
        "Reproduce with <code>motiontrack sweep --replay " + _e(folder) + " -o NEW_DIR</code>.</p>",
        "<section id=\"key-metrics\"><h2>Key metrics (mean over sequences)</h2>",
        _key_metrics(summary or rows, keys, best_run),
        f"<p class=\"small\">{BEST_MARK} marks the best run (highest mean {BEST_METRIC}) in the "
        "tables below; the figures star it.</p></section>",
        "<h2>Sequences and ground truth</h2>",
        _table(seqs, ["name", "group", "source", "gt"], text_cols=["name", "group", "source", "gt"]),
        "<h2>Swept parameters</h2>", _table(grid_rows, ["parameter", "values"], ["parameter", "values"]),
        "<h2>Evaluation parameters</h2>", _kv(ev),
        "<h2>Figures</h2>", _figures(folder),
        "<h2>Summary (mean over sequences)</h2>", _table(summary, sum_cols, best_run=best_run),
        "<h2>All runs × sequences</h2>", _table(rows, all_cols, ["sequence", "group"],
                                                  best_run=best_run),
        "<h2>Annotated clips</h2>", _clips(folder, report_dir),
        "<h2>Base tracker parameters</h2>",
        f"<p class=\"small\">Those of the stages in use; {left_out} parameter(s) of stages "
        "and methods no run used are left out.</p>" if left_out else "",
        _base_table(params, {g["key"]: list(g["values"]) for g in meta.get("grid", [])}),
        "<h2>Software</h2>", _kv(meta.get("versions", {})),
        "</body></html>",
    ]
    return "\n".join(out) + "\n"


def write_report(folder: str | Path, path: str | Path) -> str:
    """Write the report of ``folder`` to ``path`` (atomically); returns the path."""
    atomic_write_text(path, build_report(folder, path))
    return str(path)
