"""Result tables of studies: rows of one run × sequence (or one run, one trial) written as CSV
(and Parquet when ``pyarrow`` is installed) and read back with their numbers, and the per-run
averages over sequences (``summary.csv``)."""

from __future__ import annotations

import csv
import io
import logging
import math
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from ..errors import InputError, printable
from ..io.atomic import atomic_write_bytes, atomic_write_text

log = logging.getLogger(__name__)

__all__ = ["write_table", "read_table", "summarise_runs"]


def _cell(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else repr(v)
    return str(v)


def write_table(rows: Sequence[Mapping[str, Any]], path: str | Path) -> list[str]:
    """Write rows (all with the same keys, in order) as CSV (atomic), and as Parquet next to it
    when ``pyarrow`` is installed. Floats are written with ``repr`` (exact round trip).

    Returns the paths written.
    """
    path = Path(path)
    cols = list(rows[0].keys()) if rows else ["run", "sequence"]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for r in rows:
        w.writerow([_cell(r.get(c, "")) for c in cols])
    atomic_write_text(path, buf.getvalue())
    written = [str(path)]
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        log.debug("pyarrow not installed: no Parquet table")
        return written
    table = pa.table({c: [r.get(c) for r in rows] for c in cols})
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    pq_path = path.with_suffix(".parquet")
    atomic_write_bytes(pq_path, sink.getvalue().to_pybytes())
    written.append(str(pq_path))
    return written


def _uncell(text: str) -> Any:
    if text in ("true", "false"):
        return text == "true"
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def read_table(path: str | Path, required: Sequence[str] = ()) -> list[dict[str, Any]]:
    """Read a table written by :func:`write_table` (numbers parsed back to int/float).

    Raises
    ------
    InputError
        No such file, not UTF-8 text, no header, a repeated column or one of ``required``
        missing, a row with more or fewer fields than the header, a ``run`` that is not an
        integer.
    """
    p = Path(path)
    shown = printable(p)
    if not p.is_file():
        raise InputError(f"results table not found: {shown}")
    try:
        with open(p, newline="", encoding="utf-8") as fh:
            header, *body = [r for r in csv.reader(fh) if r] or [[]]
    except UnicodeDecodeError as exc:
        raise InputError(f"malformed {shown}: not UTF-8 text (byte {exc.start})") from None
    except csv.Error as exc:  # e.g. a field over the csv module's size limit
        raise InputError(f"malformed {shown}: {printable(exc)}") from None
    if not header:
        raise InputError(f"malformed {shown}: empty, expected a header row")
    if len(set(header)) != len(header):
        raise InputError(f"malformed {shown}: repeated column names in the header")
    missing = [c for c in required if c not in header]
    if missing:
        raise InputError(f"malformed {shown}: no {', '.join(missing)} "
                         f"column{'s' if len(missing) > 1 else ''}")
    rows = []
    for n, r in enumerate(body, 2):
        if len(r) != len(header):
            raise InputError(f"malformed {shown}: row {n} has {len(r)} fields, the header "
                             f"{len(header)}")
        row = {k: (v if k in ("sequence", "group") else _uncell(v)) for k, v in zip(header, r)}
        if "run" in row and (isinstance(row["run"], bool) or not isinstance(row["run"], int)):
            raise InputError(f"malformed {shown}: row {n}: run must be an integer, got "
                             f"{printable(repr(r[header.index('run')][:20]))}")
        rows.append(row)
    return rows


def summarise_runs(rows: Sequence[Mapping[str, Any]], keys: Sequence[str]) -> list[dict[str, Any]]:
    """Average every metric over the sequences of each run (nan-aware): one row per run, with
    ``sequences`` = how many were averaged. A column of integers whose mean is a whole number
    (frames, tracks; always with one sequence) stays an integer."""
    out: list[dict[str, Any]] = []
    by_run: dict[int, list[Mapping[str, Any]]] = {}
    for r in rows:
        by_run.setdefault(int(r["run"]), []).append(r)
    for run in sorted(by_run):
        rs = by_run[run]
        row: dict[str, Any] = {"run": run, "sequences": len(rs)}
        row.update({k: rs[0][k] for k in keys})
        for c in rs[0]:
            if c in ("run", "sequence", "group") or c in keys:
                continue
            whole = [x[c] for x in rs]
            if all(isinstance(v, int) and not isinstance(v, bool) for v in whole) \
                    and sum(whole) % len(whole) == 0:
                row[c] = sum(whole) // len(whole)   # counts stay integers: 40, not 40.0
                continue
            vals = np.array([float(x[c]) for x in rs], dtype=np.float64)
            finite = vals[~np.isnan(vals)]
            row[c] = float(finite.mean()) if len(finite) else float("nan")
        out.append(row)
    return out


#: the metrics of the console table of a sweep, after the run and its parameters
SUMMARY_METRICS = ("det_pixel_precision", "det_pixel_recall", "det_object_f1", "HOTA", "MOTA",
                   "IDF1")


def format_summary(summary: Sequence[Mapping[str, Any]], keys: Sequence[str],
                   metrics: Sequence[str] = SUMMARY_METRICS) -> str:
    """The per-run summary as a text table: ``run``, each parameter of ``keys`` and the
    ``metrics`` the rows hold, every column as wide as its longest cell (names are never
    cut), numbers right-aligned (floats to 4 significant digits)."""
    cols = ["run", *keys, *(m for m in metrics if not summary or m in summary[0])]

    def cell(v: Any) -> str:
        return f"{v:.4g}" if isinstance(v, float) else str(v)

    body = [[cell(r.get(c, "")) for c in cols] for r in summary]
    widths = [max([len(c)] + [len(b[i]) for b in body]) for i, c in enumerate(cols)]
    lines = ["  ".join(f"{c:>{w}}" for c, w in zip(cols, widths))]
    lines += ["  ".join(f"{v:>{w}}" for v, w in zip(b, widths)) for b in body]
    return "\n".join(lines) + "\n"
