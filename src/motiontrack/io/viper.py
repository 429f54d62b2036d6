"""ViPER XML (``.xgtf`` / ``.xml``): read ground truth / results, write our tracks as a result file.

ViPER (Video Performance Evaluation Resource, University of Maryland; Doermann & Mihalcik 2000,
"Tools and techniques for video performance evaluation") stores annotations as::

    <viper xmlns="http://lamp.cfar.umd.edu/viper#" xmlns:data="http://lamp.cfar.umd.edu/viperdata#">
      <config>
        <descriptor name="Person" type="OBJECT">
          <attribute dynamic="true" name="Location" type="http://lamp.cfar.umd.edu/viperdata#bbox"/>
        </descriptor>
      </config>
      <data><sourcefile filename="...">
        <file id="0" name="Information"> ... NUMFRAMES, H-FRAME-SIZE, V-FRAME-SIZE ... </file>
        <object framespan="1:74" id="0" name="Person">
          <attribute name="Location">
            <data:bbox framespan="1:46" x="215" y="76" width="59" height="113"/>
          </attribute>
        </object>
      </sourcefile></data>
    </viper>

Conventions (documented in ``docs/framewise.md``)
-------------------------------------------------
* **Frames**: a ViPER framespan ``"a:b"`` is inclusive at both ends and ViPER numbers frames from 1
  (ViPER-GT shows the first frame of a video as frame 1; ViPER-PE prints ``For frame 1`` for data at
  ``framespan="1:1"``). Our :class:`~motiontrack.types.Annotations` are 1-based as well, so the
  mapping is the identity: ViPER frame *f* is our frame *f*. A span ``"1:46"`` becomes 46 rows.
* **Boxes**: ``x, y`` is the top-left corner, ``width, height`` integers; the box covers the
  half-open pixel range ``[x, x + width) x [y, y + height)`` (area ``width * height``, exactly what
  ViPER-PE's polygon areas give), identical to our ``(x, y, w, h)``.
* **ids** come from the object's ``id`` attribute. Non-bbox attributes (e.g. ``Name``) go into
  ``meta["names"]`` (id -> value of the first static ``svalue`` attribute).
* ``meta`` also holds ``frame_size`` ``(H-FRAME-SIZE, V-FRAME-SIZE)`` when the Information file
  descriptor gives it (ViPER-PE clips all shapes to this frame), ``num_frames``, ``descriptor``,
  ``attribute``, ``sourcefile``.

Parsing uses :mod:`defusedxml`: DTDs with entity declarations and external entities are refused
with :class:`~motiontrack.errors.InputError`.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path
from typing import Callable, Iterable
from xml.etree.ElementTree import Element, ParseError, TreeBuilder
from xml.sax.saxutils import quoteattr

import defusedxml.ElementTree as DET
import numpy as np
from defusedxml import DefusedXmlException

from ..errors import InputError, excerpt, location, printable
from ..types import INT_LIMIT, Annotations
from .atomic import atomic_write_text
from .xmlsafe import MAX_ROWS, tag_text, unsafe_xml_reason

__all__ = ["read_viper", "parse_viper", "write_viper", "format_viper", "VIPER_NS", "VIPERDATA_NS"]

log = logging.getLogger(__name__)

VIPER_NS = "http://lamp.cfar.umd.edu/viper#"
VIPERDATA_NS = "http://lamp.cfar.umd.edu/viperdata#"
_V = "{" + VIPER_NS + "}"
_D = "{" + VIPERDATA_NS + "}"
_SPAN_RE = re.compile(r"^\s*(\d+)\s*:\s*(\d+)\s*$")


class _LineTreeBuilder(TreeBuilder):
    """A TreeBuilder that remembers the source line of every element (for error messages)."""

    def __init__(self) -> None:
        super().__init__()
        self.parser = None
        self.lines: dict[int, int] = {}

    def start(self, tag, attrs):  # noqa: D401 - TreeBuilder API
        elem = super().start(tag, attrs)
        expat = getattr(self.parser, "parser", None)  # the pure-Python XMLParser's expat parser
        if expat is not None:
            self.lines[id(elem)] = expat.CurrentLineNumber
        return elem


def _parse_framespan(text: str, where: str) -> list[tuple[int, int]]:
    """``"1:5 8:10"`` -> ``[(1, 5), (8, 10)]`` (inclusive ranges, 1-based)."""
    spans = []
    for part in text.split():
        m = _SPAN_RE.match(part)
        if not m:
            raise InputError(f"{where}: framespan must look like 'a:b' (e.g. '1:74'), got "
                             f"{excerpt(part)}")
        if max(len(m.group(1)), len(m.group(2))) > 18:  # beyond any frame number (and int64)
            raise InputError(f"{where}: framespan frame out of range, got {excerpt(part)}")
        a, b = int(m.group(1)), int(m.group(2))
        if b < a:
            raise InputError(f"{where}: framespan end < start in {excerpt(part)}")
        spans.append((a, b))
    if not spans:
        raise InputError(f"{where}: empty framespan")
    return spans


def read_viper(
    path: str | Path, descriptor: str | None = None, attribute: str | None = None
) -> Annotations:
    """Read a ViPER XML file (``.xgtf``/``.xml``) into :class:`Annotations`.

    Parameters
    ----------
    path : the file.
    descriptor : OBJECT descriptor name to read (e.g. ``"Person"``); default: every OBJECT descriptor
        that has a bbox attribute (ids must then be unique across descriptors).
    attribute : name of the bbox attribute (default: the first bbox attribute of the descriptor).

    Returns
    -------
    Annotations
        One row per (object, frame) where the bbox attribute is defined; frames 1-based (ViPER frame
        numbers unchanged), ``ids`` the ViPER object ids, ``boxes`` ``(N, 4) float64`` x, y, w, h.

    Raises
    ------
    InputError
        File missing, not well-formed XML (message gives line and column), forbidden DTD/entities,
        or a malformed element (message gives the element and its line).
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"ViPER file not found: {p}")
    data = p.read_bytes()
    ann = parse_viper(data, name=str(p), descriptor=descriptor, attribute=attribute)
    return Annotations(
        **{c: getattr(ann, c) for c in
           ("frames", "ids", "boxes", "scores", "consider", "classes", "visibility", "world")},
        meta={**ann.meta, "path": str(p)},
    )


def parse_viper(
    data: bytes | str,
    name: str = "<string>",
    descriptor: str | None = None,
    attribute: str | None = None,
) -> Annotations:
    """Parse ViPER XML given as bytes/str; see :func:`read_viper`."""
    name = location(name)
    root, where = _parse_tree(data, name)
    if root.tag != _V + "viper":
        raise InputError(f"{where(root)}: root element must be <viper> in namespace {VIPER_NS}")
    config = root.find(_V + "config")
    if config is None:
        raise InputError(f"{where(root)}: missing <config>")
    # 1. config: which OBJECT descriptors have which bbox attributes
    bbox_attrs = _bbox_attributes(config, descriptor, attribute, where)
    if descriptor is not None and descriptor not in bbox_attrs:
        raise InputError(
            f"{name}: no OBJECT descriptor {descriptor!r} with a bbox attribute"
            + (f" named {attribute!r}" if attribute else "")
        )
    rows = _Rows()
    meta: dict[str, object] = {"format": "viper"}
    data_el = root.find(_V + "data")
    sourcefiles = [] if data_el is None else data_el.findall(_V + "sourcefile")
    if len(sourcefiles) > 1:
        log.warning("%s: %d sourcefiles; reading all into one table", name, len(sourcefiles))
    for sf in sourcefiles:
        meta.setdefault("sourcefile", sf.get("filename", ""))
        # 2. the Information FILE descriptor: frame count and size
        for fel in sf.findall(_V + "file"):
            _read_information(fel, meta, where)
        # 3. objects
        for obj in sf.findall(_V + "object"):
            if obj.get("name") in bbox_attrs:
                _read_object(obj, bbox_attrs[obj.get("name")], rows, where)
    if bbox_attrs:
        meta["descriptor"] = next(iter(bbox_attrs)) if len(bbox_attrs) == 1 else sorted(bbox_attrs)
        meta["attribute"] = next(iter(bbox_attrs.values()))
    meta["names"] = rows.names
    return rows.annotations(meta, name)


def _parse_tree(data: bytes | str, name: str) -> tuple[Element, Callable[[Element], str]]:
    """The root element, and ``where(el)`` naming an element and its source line for errors."""
    builder = _LineTreeBuilder()
    parser = DET.DefusedXMLParser(
        target=builder, forbid_dtd=False, forbid_entities=True, forbid_external=True
    )
    builder.parser = parser
    try:
        parser.feed(data)
        root = parser.close()
    except DefusedXmlException as exc:
        raise InputError(f"{name}: refused unsafe XML: {unsafe_xml_reason(exc)}") from None
    except ParseError as exc:
        # expat's message ("not well-formed (invalid token): line 3, column 5") quotes nothing
        line, col = getattr(exc, "position", (None, None))
        raise InputError(f"{name}: not well-formed XML at line {line}, column {col}: "
                         f"{printable(exc)}") from None
    except LookupError:  # an XML declaration naming an unknown encoding
        raise InputError(f"{name}: unsupported XML encoding in the XML declaration") from None
    lines = builder.lines

    def where(el: Element) -> str:
        tag = el.tag.split("}")[-1]
        return f"{name}: line {lines.get(id(el), '?')}: <{tag_text(tag)}>"

    return root, where


def _bbox_attributes(config: Element, descriptor: str | None, attribute: str | None,
                     where: Callable[[Element], str]) -> dict[str, str]:
    """``{descriptor name: bbox attribute name}`` of the OBJECT descriptors to read, file order."""
    bbox_attrs: dict[str, str] = {}
    for desc in config.findall(_V + "descriptor"):
        if desc.get("type") != "OBJECT":
            continue
        dname = desc.get("name")
        if dname is None:
            raise InputError(f"{where(desc)}: descriptor without a name")
        if descriptor is not None and dname != descriptor:
            continue
        for att in desc.findall(_V + "attribute"):
            if (att.get("type") or "").endswith("#bbox") and (
                attribute is None or att.get("name") == attribute
            ):
                bbox_attrs[dname] = att.get("name")
                break
    return bbox_attrs


def _read_information(fel: Element, meta: dict[str, object],
                      where: Callable[[Element], str]) -> None:
    """``num_frames`` and ``frame_size`` from an Information ``<file>`` element into ``meta``."""
    info = {}
    for att in fel.findall(_V + "attribute"):
        for val in att:
            if val.get("value") is not None:
                info[att.get("name")] = val.get("value")
    def number(key: str) -> int:
        return _int(info[key], f"{where(fel)}: Information {key} must be an integer in "
                               f"[0, 2**62)", lo=0)

    if "NUMFRAMES" in info:
        meta["num_frames"] = number("NUMFRAMES")
    if "H-FRAME-SIZE" in info and "V-FRAME-SIZE" in info:
        meta["frame_size"] = (number("H-FRAME-SIZE"), number("V-FRAME-SIZE"))


def _int(raw: str | None, message: str, label: str = "", lo: int = -INT_LIMIT) -> int:
    """An integer attribute in ``[lo, 2**62)``; otherwise :class:`InputError` with ``message``
    and a short excerpt of what was there (``label=`` before it)."""
    text = "" if raw is None else raw.strip()
    try:
        v = int(text) if len(text) <= 20 else None
    except ValueError:
        v = None
    if v is None or not lo <= v < INT_LIMIT:
        raise InputError(f"{message}, got {label + '=' if label else ''}{excerpt(text)}")
    return v


def _read_object(obj: Element, bbox_attr: str, rows: "_Rows",
                 where: Callable[[Element], str]) -> None:
    """One ``<object>``: a row per frame of its bbox attribute, its name from an ``svalue``."""
    oid = rows.claim_id(obj, where)
    _parse_framespan(obj.get("framespan", ""), where(obj))
    for att in obj.findall(_V + "attribute"):
        aname = att.get("name")
        if aname != bbox_attr:
            for val in att:
                if val.tag == _D + "svalue" and val.get("value") is not None:
                    rows.names.setdefault(oid, val.get("value"))
            continue
        for val in att:
            x, y, w, h = _bbox(val, aname, where)
            for a, b in _parse_framespan(val.get("framespan", ""), where(val)):
                if len(rows.frames) + (b - a + 1) > MAX_ROWS:
                    raise InputError(f"{where(val)}: framespan {a}:{b} would make more than "
                                     f"{MAX_ROWS} rows")
                rows.add(range(a, b + 1), oid, (x, y, w, h))


def _bbox(val: Element, aname: str, where: Callable[[Element], str]) -> tuple[int, int, int, int]:
    """``x, y, width, height`` of a ``<data:bbox>`` element (integers, sizes >= 0)."""
    if val.tag != _D + "bbox":
        raise InputError(f"{where(val)}: expected <data:bbox> in attribute {excerpt(aname)}")
    x, y, w, h = (_int(val.get(k), f"{where(val)}: bbox needs integer x, y, width, height "
                                   "(|value| < 2**62)", k)
                  for k in ("x", "y", "width", "height"))
    if w < 0 or h < 0:
        raise InputError(f"{where(val)}: bbox width/height must be >= 0, "
                         f"got width={w}, height={h}")
    return x, y, w, h


class _Rows:
    """The rows read so far (one per object and frame), the ids taken and the objects' names."""

    def __init__(self) -> None:
        self.frames: list[int] = []
        self.ids: list[int] = []
        self.boxes: list[tuple[int, int, int, int]] = []
        self.names: dict[int, str] = {}
        self.seen: dict[int, str] = {}

    def claim_id(self, obj: Element, where: Callable[[Element], str]) -> int:
        """The object's integer id, refused when another object already has it."""
        dname = obj.get("name")
        oid = _int(obj.get("id"), f"{where(obj)}: object id must be an integer (|id| < 2**62)")
        if oid in self.seen and self.seen[oid] != dname:
            raise InputError(f"{where(obj)}: object id {oid} used by descriptors "
                             f"{excerpt(self.seen[oid])} and {excerpt(dname)}; pass descriptor=")
        if oid in self.seen:
            raise InputError(f"{where(obj)}: duplicate object id {oid}")
        self.seen[oid] = dname
        return oid

    def add(self, frames: Iterable[int], oid: int, box: tuple[int, int, int, int]) -> None:
        for f in frames:
            self.frames.append(f)
            self.ids.append(oid)
            self.boxes.append(box)

    def annotations(self, meta: dict[str, object], name: str) -> Annotations:
        """The rows sorted by (frame, id) for a canonical order; duplicate (frame, id) refused."""
        f_arr = np.asarray(self.frames, dtype=np.int64)
        i_arr = np.asarray(self.ids, dtype=np.int64)
        b_arr = np.asarray(self.boxes, dtype=np.float64).reshape(-1, 4)
        order = np.lexsort((i_arr, f_arr))
        f_arr, i_arr, b_arr = f_arr[order], i_arr[order], b_arr[order]
        if len(f_arr) > 1:
            dup = (np.diff(f_arr) == 0) & (np.diff(i_arr) == 0)
            if dup.any():
                k = int(np.flatnonzero(dup)[0])
                raise InputError(f"{name}: object {int(i_arr[k])} has two boxes at frame "
                                 f"{int(f_arr[k])} (overlapping framespans)")
        return Annotations.from_columns(f_arr, i_arr, b_arr, meta=meta)


def _runs(frames: np.ndarray, boxes: np.ndarray) -> Iterable[tuple[int, int, tuple[int, ...]]]:
    """Group consecutive frames with an identical box into ``(start, end, box)`` runs."""
    start = 0
    n = len(frames)
    for k in range(1, n + 1):
        if (
            k == n
            or frames[k] != frames[k - 1] + 1
            or not (boxes[k] == boxes[k - 1]).all()
        ):
            yield int(frames[start]), int(frames[k - 1]), tuple(int(v) for v in boxes[start])
            start = k


def _spans_text(frames: np.ndarray) -> str:
    parts = []
    start = 0
    for k in range(1, len(frames) + 1):
        if k == len(frames) or frames[k] != frames[k - 1] + 1:
            parts.append(f"{int(frames[start])}:{int(frames[k - 1])}")
            start = k
    return " ".join(parts)


def format_viper(
    ann: Annotations,
    descriptor: str = "Person",
    attribute: str = "Location",
    frame_size: tuple[int, int] | None = None,
    num_frames: int | None = None,
    sourcefile: str = "video",
) -> str:
    """ViPER XML text for ``ann`` (see :func:`write_viper`)."""
    if len(ann) and (ann.frames < 1).any():
        raise InputError("ViPER frames are 1-based; got a frame < 1")
    boxes = np.rint(ann.boxes).astype(np.int64) if len(ann) else np.zeros((0, 4), np.int64)
    if len(ann) and not np.array_equal(boxes, ann.boxes):
        log.warning("ViPER boxes are integers: rounding %d non-integer box(es) to the nearest "
                    "pixel", int((boxes != ann.boxes).any(axis=1).sum()))
    if num_frames is None:
        num_frames = int(ann.frames.max()) if len(ann) else 0
    out = _header_xml(descriptor, attribute, frame_size, num_frames, sourcefile)
    for oid in np.unique(ann.ids):
        out += _object_xml(ann, boxes, oid, descriptor, attribute)
    out += ["        </sourcefile>", "    </data>", "</viper>", ""]
    return "\n".join(out)


def _header_xml(descriptor: str, attribute: str, frame_size: tuple[int, int] | None,
                num_frames: int, sourcefile: str) -> list[str]:
    """Lines from the XML declaration to the end of the Information ``<file>`` element."""
    q = quoteattr
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<viper xmlns="{VIPER_NS}" xmlns:data="{VIPERDATA_NS}">',
        "    <config>",
        '        <descriptor name="Information" type="FILE">',
        f'            <attribute dynamic="false" name="NUMFRAMES" type="{VIPERDATA_NS}dvalue"/>',
        f'            <attribute dynamic="false" name="H-FRAME-SIZE" type="{VIPERDATA_NS}dvalue"/>',
        f'            <attribute dynamic="false" name="V-FRAME-SIZE" type="{VIPERDATA_NS}dvalue"/>',
        "        </descriptor>",
        f"        <descriptor name={q(descriptor)} type=\"OBJECT\">",
        f'            <attribute dynamic="true" name={q(attribute)} type="{VIPERDATA_NS}bbox"/>',
        "        </descriptor>",
        "    </config>",
        "    <data>",
        f"        <sourcefile filename={q(sourcefile)}>",
        '            <file id="0" name="Information">',
        f'                <attribute name="NUMFRAMES"><data:dvalue value="{num_frames}"/></attribute>',
    ]
    if frame_size is not None:
        out += [
            f'                <attribute name="H-FRAME-SIZE"><data:dvalue value="{int(frame_size[0])}"/>'
            "</attribute>",
            f'                <attribute name="V-FRAME-SIZE"><data:dvalue value="{int(frame_size[1])}"/>'
            "</attribute>",
        ]
    out.append("            </file>")
    return out


def _object_xml(ann: Annotations, boxes: np.ndarray, oid: np.int64, descriptor: str,
                attribute: str) -> list[str]:
    """Lines of one ``<object>``: its frames as spans, runs of one box as ``<data:bbox>``."""
    q = quoteattr
    rows = np.flatnonzero(ann.ids == oid)
    rows = rows[np.argsort(ann.frames[rows], kind="stable")]
    fr = ann.frames[rows]
    if len(fr) > 1 and (np.diff(fr) == 0).any():
        raise InputError(f"id {int(oid)} has two boxes in one frame; ViPER cannot store that")
    out = [f'            <object framespan="{_spans_text(fr)}" id="{int(oid)}" '
           f"name={q(descriptor)}>",
           f"                <attribute name={q(attribute)}>"]
    for a, b, (x, y, w, h) in _runs(fr, boxes[rows]):
        out.append(f'                    <data:bbox framespan="{a}:{b}" height="{h}" '
                   f'width="{w}" x="{x}" y="{y}"/>')
    out.append("                </attribute>")
    out.append("            </object>")
    return out


def write_viper(
    ann: Annotations,
    path: str | Path,
    descriptor: str = "Person",
    attribute: str = "Location",
    frame_size: tuple[int, int] | None = None,
    num_frames: int | None = None,
    sourcefile: str = "video",
) -> None:
    """Write ``ann`` (our tracks or ground truth) as a ViPER result file, atomically.

    One ``<object>`` per id with a dynamic bbox attribute; consecutive frames with the same box are
    merged into one ``framespan="a:b"`` (inclusive, 1-based like our frames). ViPER boxes are
    integers: non-integer boxes are rounded to the nearest pixel (a warning is logged), so integer
    boxes read back exactly with :func:`read_viper`.

    Parameters
    ----------
    ann : rows to write (frames 1-based, ids, boxes x, y, w, h).
    path : output file (``.xgtf`` or ``.xml``).
    descriptor, attribute : ViPER OBJECT descriptor and bbox attribute names.
    frame_size : ``(width, height)`` in pixels for the Information descriptor (ViPER-PE clips shapes
        to it); default ``ann.meta["frame_size"]`` if present.
    num_frames : NUMFRAMES; default the last frame.
    sourcefile : the ``<sourcefile filename=...>``.
    """
    if frame_size is None:
        fs = ann.meta.get("frame_size") if ann.meta else None
        frame_size = tuple(fs) if fs is not None else None  # type: ignore[assignment]
    atomic_write_text(
        path,
        format_viper(ann, descriptor, attribute, frame_size, num_frames, sourcefile),
    )
