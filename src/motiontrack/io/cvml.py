"""PETS CVML XML (the ground-truth format of PETS 2009 and of A. Milan's PETS annotations).

Layout::

    <dataset name="...">
      <frame number="0">                      video frame index, 0-based
        <objectlist>
          <object id="9" ...>
            <box xc="514.71" yc="195.27" w="31.03" h="75.17"/>   centre and size, pixels
            (other children such as <orientation>, <appearance> are ignored)
          </object>
        </objectlist>
      </frame>
    </dataset>

Mapping to :class:`~motiontrack.types.Annotations`: ``frame = number + 1`` (our frames are
1-based MOTChallenge numbers; CVML numbers are the 0-based video index), ``x = xc - w/2``,
``y = yc - h/2``. CVML has no confidence, consider flag, class, visibility or world position:
reading fills the defaults (score 1, consider True, class -1, visibility -1, world -1) and writing
drops them.

Reference: J. Ferryman and A. Shahrokni, "PETS2009: Dataset and challenge", PETS 2009; the CVML
schema of T. List and R. B. Fisher, "CVML - an XML-based computer vision markup language", ICPR 2004.
"""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from ..errors import InputError
from ..types import Annotations
from .xmlsafe import MAX_ROWS, XmlNode, parse_xml, read_bytes, xml_float, xml_int
from .atomic import atomic_open

__all__ = ["read_cvml", "parse_cvml", "write_cvml", "format_cvml"]


def read_cvml(path: str | Path) -> Annotations:
    """Read a PETS CVML file; see the module docstring for the mapping.

    Raises :class:`InputError` naming the line and element of the first malformed entry.
    """
    p = Path(path)
    ann = parse_cvml(read_bytes(p), name=str(p))
    return Annotations(**_columns(ann), meta={**ann.meta, "path": str(p)})


def _columns(ann: Annotations) -> dict:
    return {k: getattr(ann, k) for k in ("frames", "ids", "boxes", "scores", "consider", "classes",
                                         "visibility", "world")}


def parse_cvml(data: bytes, name: str = "<bytes>") -> Annotations:
    """Parse CVML bytes into :class:`Annotations` (frames 1-based, boxes ``x, y, w, h``)."""
    root = parse_xml(data, name)
    if root.tag != "dataset":
        raise InputError(f"{root.where(name)}: not a PETS CVML file (root element must be "
                         f"<dataset>)")
    frames: list[int] = []
    ids: list[int] = []
    boxes: list[tuple[float, float, float, float]] = []
    for fnode in root.children:
        if fnode.tag != "frame":
            continue
        number = xml_int(fnode, "number", name, lo=0)
        seen: set[int] = set()
        for olist in fnode.find_all("objectlist"):
            for obj in olist.find_all("object"):
                oid = xml_int(obj, "id", name)
                if oid in seen:
                    raise InputError(f"{obj.where(name)}: object id={oid} appears twice in frame "
                                     f"number={number}")
                seen.add(oid)
                box = _box(obj, name)
                frames.append(number + 1)
                ids.append(oid)
                boxes.append(box)
    meta = {"format": "cvml"}
    if "name" in root.attrib:
        meta["name"] = root.attrib["name"]
    if not frames:
        return Annotations(**_columns(Annotations.empty()), meta=meta)
    return Annotations.from_columns(frames, ids, np.asarray(boxes, dtype=np.float64), meta=meta)


def _box(obj: XmlNode, name: str) -> tuple[float, float, float, float]:
    bnode = obj.find("box")
    if bnode is None:
        raise InputError(f"{obj.where(name)}: object without a <box>")
    xc, yc = xml_float(bnode, "xc", name), xml_float(bnode, "yc", name)
    w, h = xml_float(bnode, "w", name), xml_float(bnode, "h", name)
    if w <= 0 or h <= 0:
        raise InputError(f"{bnode.where(name)}: box width and height must be > 0, got w={w}, h={h}")
    return (xc - w / 2.0, yc - h / 2.0, w, h)


def _num(v: float) -> str:
    return f"{float(v):.12g}"


def format_cvml(ann: Annotations, dataset_name: str | None = None) -> str:
    """CVML text for ``ann``: one ``<frame>`` per frame from the first to the last annotated
    frame (frames without boxes get an empty ``<objectlist/>``), objects sorted by id."""
    name = dataset_name if dataset_name is not None else str(ann.meta.get("name", "motiontrack"))
    out = ["<?xml version='1.0' encoding='utf-8'?>\n", f"<dataset name={quoteattr(name)}>\n"]
    if len(ann):
        if ann.frames.min() < 1:
            raise InputError(f"cannot write CVML: frame numbers must be >= 1, got "
                             f"{int(ann.frames.min())}")
        span = int(ann.frames.max()) - int(ann.frames.min()) + 1
        if span > MAX_ROWS:
            raise InputError(f"cannot write CVML: frames {int(ann.frames.min())} to "
                             f"{int(ann.frames.max())} would be {span} <frame> elements, more "
                             f"than {MAX_ROWS}")
        groups = ann.by_frame()
        for f in range(int(ann.frames.min()), int(ann.frames.max()) + 1):
            rows = groups.get(f)
            if rows is None:
                out.append(f'   <frame number="{f - 1}">\n      <objectlist />\n   </frame>\n')
                continue
            rows = rows[np.argsort(ann.ids[rows], kind="stable")]
            out.append(f'   <frame number="{f - 1}">\n      <objectlist>\n')
            for r in rows:
                x, y, w, h = ann.boxes[r]
                out.append(f'         <object id="{int(ann.ids[r])}">\n'
                           f'            <box h="{_num(h)}" w="{_num(w)}" xc="{_num(x + w / 2.0)}" '
                           f'yc="{_num(y + h / 2.0)}" />\n         </object>\n')
            out.append("      </objectlist>\n   </frame>\n")
    out.append("</dataset>\n")
    return "".join(out)


def write_cvml(ann: Annotations, path: str | Path, dataset_name: str | None = None) -> None:
    """Write ``ann`` as PETS CVML (atomically). Scores, consider flags, classes, visibility and
    world positions are not part of CVML and are dropped."""
    text = format_cvml(ann, dataset_name)
    with atomic_open(path) as fh:
        fh.write(text)
