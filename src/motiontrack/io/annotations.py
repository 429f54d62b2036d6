"""Read and write annotation files in any supported format, detected by content.

Formats (see ``docs/formats.md``):

======== ============================== ==================================================
name     detected by                    module
======== ============================== ==================================================
``mot``  numeric comma/space rows       :mod:`motiontrack.io.mot` (MOTChallenge CSV)
``viper``XML root ``<viper>``           :mod:`motiontrack.io.viper` (ViPER ``.xgtf``/``.xml``)
``cvml`` XML root ``<dataset>``         :mod:`motiontrack.io.cvml` (PETS CVML)
``cvat`` XML root ``<annotations>``     :mod:`motiontrack.io.cvat` (CVAT for video 1.1)
``json`` first character ``{``          :mod:`motiontrack.io.jsonfmt` (ours)
======== ============================== ==================================================

The safe XML parser the CVML and CVAT readers share is :mod:`motiontrack.io.xmlsafe`.
"""

from __future__ import annotations

import dataclasses
import logging
import re
from pathlib import Path

from ..errors import ConfigError, InputError, excerpt, location, require_file, token_at
from ..types import Annotations
from .cvat import read_cvat, write_cvat
from .cvml import read_cvml, write_cvml
from .jsonfmt import read_json, write_json
from .mot import read_mot, read_seqinfo, write_mot
from .viper import read_viper, write_viper
from .xmlsafe import tag_text

__all__ = [
    "FORMATS",
    "detect_format",
    "read_annotations",
    "read_ground_truth",
    "write_annotations",
]

log = logging.getLogger(__name__)

FORMATS = ("mot", "viper", "cvml", "cvat", "json")
_WRITE_FORMATS = ("mot", "mot-gt", "viper", "cvml", "cvat", "json")
_XML_ROOTS = {"dataset": "cvml", "annotations": "cvat", "viper": "viper"}
_SNIFF_BYTES = 65536


# ---------------------------------------------------------------------------------------------
# Detection and dispatch
# ---------------------------------------------------------------------------------------------

_ROOT_RE = re.compile(rb"<\s*([A-Za-z_][\w.\-]*:)?([A-Za-z_][\w.\-]*)")
_MOT_LINE_RE = re.compile(r"^\s*[-+]?\d+(\.\d*)?([eE][-+]?\d+)?\s*[,\s]")


def _strip_prolog(head: bytes) -> bytes:
    """Drop BOM, XML declaration, comments, processing instructions and DOCTYPE."""
    head = head.lstrip(b"\xef\xbb\xbf").lstrip()
    while True:
        if head.startswith(b"<?"):
            term = b"?>"
        elif head.startswith(b"<!--"):
            term = b"-->"
        elif head.startswith(b"<!"):
            bracket, close = head.find(b"["), head.find(b">")
            term = b"]>" if 0 <= bracket < close else b">"  # DOCTYPE with an internal subset
        else:
            return head
        end = head.find(term)
        if end < 0:
            return head
        head = head[end + len(term):].lstrip()


def detect_format(path: str | Path) -> str:
    """The format of an annotation file by its content (not its name).

    Returns one of :data:`FORMATS`. Raises :class:`InputError` when the content fits none.
    """
    p = Path(path)
    _check_file(p)
    with open(p, "rb") as fh:
        head = fh.read(_SNIFF_BYTES)
    if not head.strip(b"\xef\xbb\xbf \t\r\n"):
        raise InputError(f"{location(p)}: empty annotation file")
    body = _strip_prolog(head)
    if body.startswith(b"{"):
        return "json"
    if body.startswith(b"<") or head.lstrip(b"\xef\xbb\xbf").lstrip().startswith(b"<"):
        m = _ROOT_RE.match(body)
        if not m:
            raise InputError(f"{location(p)}: XML without a recognisable root element")
        root = m.group(2).decode("ascii", "replace")
        fmt = _XML_ROOTS.get(root.lower())
        if fmt is None:
            raise InputError(f"{location(p)}: unknown XML annotation format with root element "
                             f"<{tag_text(root)}> (expected <viper>, <dataset> (PETS CVML) or "
                             f"<annotations> (CVAT))")
        return fmt
    try:
        text = head.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        if exc.start < len(head) - 4:  # not just a multi-byte character cut by the sniff limit
            raise InputError(f"{location(p)}: not a text annotation file (undecodable byte at "
                             f"offset {exc.start})") from None
        text = head[: exc.start].decode("utf-8-sig")
    for lineno, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if _MOT_LINE_RE.match(line):
            return "mot"
        col = len(line) - len(line.lstrip())
        raise InputError(f"{location(p, lineno, col + 1)}: unknown annotation format: expected "
                         f"MOTChallenge CSV (a row of numbers), XML or JSON, got "
                         f"{excerpt(token_at(line, col))}")
    raise InputError(f"{location(p)}: no annotation rows found")


def _check_file(p: Path) -> None:
    """:class:`InputError` unless ``p`` is a regular file."""
    require_file(p, "annotation file")


def read_annotations(path: str | Path, kind: str = "auto", mot_kind: str = "auto") -> Annotations:
    """Read ground truth, results or detections from any supported file.

    Parameters
    ----------
    path : annotation file.
    kind : the format: ``"auto"`` (detect by content, :func:`detect_format`) or one of
        :data:`FORMATS`.
    mot_kind : for MOTChallenge CSV only, passed to :func:`motiontrack.io.mot.read_mot`
        (``"gt"``, ``"results"``, ``"det"`` or ``"auto"`` by file name).

    Returns
    -------
    Annotations
        Frames 1-based; ``meta["format"]`` names the format read.

    Raises
    ------
    InputError
        Missing, unknown or malformed file (the message names the file and the line/element).
    ConfigError
        Unknown ``kind``.
    """
    if kind != "auto" and kind not in FORMATS:
        raise ConfigError(f"unknown annotation format {kind!r}; expected 'auto' or one of "
                          f"{', '.join(FORMATS)}")
    p = Path(path)
    _check_file(p)
    fmt = detect_format(p) if kind == "auto" else kind
    log.debug("reading %s as %s", p, fmt)
    if fmt == "mot":
        return read_mot(p, kind=mot_kind)
    return _READERS[fmt](p)


def read_ground_truth(path: str | Path, kind: str = "auto") -> Annotations:
    """Read ground truth (:func:`read_annotations`, MOTChallenge CSV read as gt) with
    ``meta["seq_length"]``: the ``seqLength`` of a MOTChallenge ``seqinfo.ini`` in the file's
    folder or the one above (``SEQ/gt/gt.txt`` beside ``SEQ/seqinfo.ini``), when there is one
    that states it. Scoring covers the frames 1 to that length
    (:func:`motiontrack.evaluate.score.gt_coverage`); a ``seqinfo.ini`` that cannot be read is
    named in a warning and left aside."""
    gt = read_annotations(path, kind=kind, mot_kind="gt")
    p = Path(path)
    for folder in (p.parent, p.parent.parent):
        ini = folder / "seqinfo.ini"
        if not ini.is_file():
            continue
        try:
            length = read_seqinfo(ini).get("seqlength")
        except InputError as exc:
            log.warning("%s; scoring the ground truth's own frames", exc)
            return gt
        if isinstance(length, int) and length >= 1:
            return dataclasses.replace(gt, meta={**gt.meta, "seq_length": length})
        return gt
    return gt


_READERS = {"viper": read_viper, "cvml": read_cvml, "cvat": read_cvat, "json": read_json}

_EXTENSIONS = {".txt": "mot", ".csv": "mot", ".json": "json", ".xgtf": "viper"}


def write_annotations(ann: Annotations, path: str | Path, fmt: str | None = None) -> str:
    """Write annotations (atomically) in the format given by ``fmt`` or the file extension.

    Parameters
    ----------
    ann : the table to write.
    path : output file.
    fmt : ``"mot"`` (results layout), ``"mot-gt"`` (ground-truth layout with the consider flag),
        ``"viper"``, ``"cvml"``, ``"cvat"`` or ``"json"``. ``None``: by extension — ``.txt``/``.csv``
        → ``mot`` (``mot-gt`` when ``ann.meta["kind"] == "gt"``), ``.json`` → ``json``,
        ``.xgtf`` → ``viper``; ``.xml`` → the format in ``ann.meta["format"]`` when that is an XML
        format (so a file read from CVML writes back as CVML), otherwise ``fmt`` is required.

    Returns
    -------
    str
        The format written.
    """
    p = Path(path)
    if fmt is None:
        ext = p.suffix.lower()
        if ext == ".xml" and ann.meta.get("format") in ("viper", "cvml", "cvat"):
            fmt = str(ann.meta["format"])  # write back in the format it was read from
        elif ext == ".xml":
            raise ConfigError(f"{p}: .xml could be ViPER, PETS CVML or CVAT; choose the format "
                              "explicitly (viper, cvml or cvat)")
        elif ext not in _EXTENSIONS:
            raise ConfigError(f"{p}: cannot tell the annotation format from the extension "
                              f"{ext or '(none)'!r}; choose one of {', '.join(_WRITE_FORMATS)}")
        else:
            fmt = _EXTENSIONS[ext]
        if fmt == "mot" and ann.meta.get("kind") == "gt":
            fmt = "mot-gt"
    if fmt not in _WRITE_FORMATS:
        raise ConfigError(f"unknown annotation format {fmt!r}; expected one of "
                          f"{', '.join(_WRITE_FORMATS)}")
    if fmt in ("mot", "mot-gt"):
        write_mot(ann, p, kind="gt" if fmt == "mot-gt" else "results")
    else:
        _WRITERS[fmt](ann, p)
    return fmt


_WRITERS = {"viper": write_viper, "cvml": write_cvml, "cvat": write_cvat, "json": write_json}
