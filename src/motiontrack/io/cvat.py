"""CVAT "for video 1.1" XML tracks (and, read-only, "for images 1.1" boxes).

Layout (CVAT's video export)::

    <annotations>
      <version>1.1</version>
      <meta><task> ... <labels><label><name>person</name>...</label></labels> ... </task></meta>
      <track id="0" label="person" source="manual">
        <box frame="0" outside="0" occluded="0" keyframe="1"
             xtl="10.0" ytl="20.0" xbr="40.0" ybr="100.0" z_order="0"/>
        ...
        <box frame="57" outside="1" .../>     the track leaves the scene: not a box
      </track>
    </annotations>

Mapping to :class:`~motiontrack.types.Annotations`:

* ``frame = frame + 1`` (CVAT frames are the 0-based task frame index; ours are 1-based).
* ``x, y, w, h = xtl, ytl, xbr - xtl, ybr - ytl``.
* ``id`` = the CVAT track id, unchanged (CVAT numbers tracks from 0; ids are only labels).
* ``outside="1"`` rows end a track segment and are not boxes: they are skipped.
* ``occluded="1"`` → visibility 0.0, ``occluded="0"`` → visibility 1.0; writing sets
  ``occluded="1"`` when ``0 <= visibility < 0.5``.
* Labels → MOTChallenge class ids where the name is a MOT17 class (``pedestrian``/``person`` 1,
  ``car`` 3, ...); other labels get ids 1000, 1001, ... in order of first appearance and the
  mapping is kept in ``meta["labels"]`` (class id → name) so that writing restores the names.
* Assumption: every frame of a track is present in the file. CVAT's video export already expands
  the interpolation between keyframes into one ``<box>`` per frame (``keyframe="0"`` for the
  interpolated ones), so the reader does **not** interpolate; a file with only keyframes reads as
  just those frames.
* Non-box shapes (polygon, points, ...) and ``<tag>`` elements are ignored; ``<image>`` elements of
  the "for images" export are read as anonymous boxes (id -1, frame = image id + 1).

Scores, consider flags and world positions are not part of CVAT: reading fills the defaults,
writing drops them.
"""

from __future__ import annotations

import logging
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from ..errors import InputError, excerpt, location
from ..types import Annotations
from .xmlsafe import XmlNode, parse_xml, read_bytes, xml_float, xml_int
from .atomic import atomic_open

__all__ = ["read_cvat", "parse_cvat", "write_cvat", "format_cvat", "MOT_CLASSES"]

log = logging.getLogger(__name__)

#: MOTChallenge (MOT16/17) class ids and names.
MOT_CLASSES = {
    1: "pedestrian", 2: "person_on_vehicle", 3: "car", 4: "bicycle", 5: "motorbike",
    6: "non_mot_vehicle", 7: "static_person", 8: "distractor", 9: "occluder",
    10: "occluder_on_ground", 11: "occluder_full", 12: "reflection", 13: "crowd",
}
_NAME_TO_CLASS = {v: k for k, v in MOT_CLASSES.items()} | {"person": 1}
_FIRST_CUSTOM_CLASS = 1000


def _norm(label: str) -> str:
    return label.strip().lower().replace(" ", "_").replace("-", "_")


def read_cvat(path: str | Path) -> Annotations:
    """Read a CVAT for video 1.1 file; see the module docstring for the mapping."""
    p = Path(path)
    ann = parse_cvat(read_bytes(p), name=str(p))
    return Annotations(**{k: getattr(ann, k) for k in (
        "frames", "ids", "boxes", "scores", "consider", "classes", "visibility", "world")},
        meta={**ann.meta, "path": str(p)})


def _flag(node: XmlNode, key: str, name: str) -> bool:
    raw = node.attrib.get(key, "0").strip()
    if raw not in ("0", "1", "true", "false", "True", "False"):
        raise InputError(f"{node.where(name)}: attribute {key}={excerpt(raw)} must be 0 or 1")
    return raw in ("1", "true", "True")


def _xyxy(node: XmlNode, name: str) -> tuple[float, float, float, float]:
    xtl, ytl = xml_float(node, "xtl", name), xml_float(node, "ytl", name)
    xbr, ybr = xml_float(node, "xbr", name), xml_float(node, "ybr", name)
    w, h = xbr - xtl, ybr - ytl
    if not (w > 0 and h > 0 and np.isfinite(w) and np.isfinite(h)):
        raise InputError(f"{node.where(name)}: box needs xbr > xtl and ybr > ytl, got "
                         f"xtl={xtl}, ytl={ytl}, xbr={xbr}, ybr={ybr}")
    return (xtl, ytl, w, h)


class _Labels:
    """Label name ↔ class id: MOT17 names first, custom ids 1000+ in order of appearance."""

    def __init__(self) -> None:
        self.custom: dict[str, int] = {}
        self.names: dict[int, str] = {}

    def class_of(self, label: str) -> int:
        key = _norm(label)
        if key in _NAME_TO_CLASS:
            cls = _NAME_TO_CLASS[key]
        else:
            cls = self.custom.setdefault(key, _FIRST_CUSTOM_CLASS + len(self.custom))
        self.names.setdefault(cls, label)
        return cls


def parse_cvat(data: bytes, name: str = "<bytes>") -> Annotations:
    """Parse CVAT XML bytes into :class:`Annotations` (frames 1-based, boxes ``x, y, w, h``)."""
    root = parse_xml(data, name)
    if root.tag != "annotations":
        raise InputError(f"{root.where(name)}: not a CVAT file (root element must be "
                         f"<annotations>)")
    version = root.find("version")
    if version is not None and version.text and version.text != "1.1":
        log.warning("%s: CVAT format version %s, expected 1.1; reading anyway", location(name),
                    excerpt(version.text))
    labels = _declared_labels(root.find("meta"))
    rows = _Rows()
    skipped = 0
    for node in root.children:
        if node.tag == "track":
            skipped += _read_track(node, name, labels, rows)
        elif node.tag == "image":  # "CVAT for images 1.1": anonymous boxes
            skipped += _read_image(node, name, labels, rows)
    if skipped:
        log.debug("%s: ignored %d non-box shapes", name, skipped)
    return rows.annotations({"format": "cvat", "labels": dict(labels.names)})


def _declared_labels(meta_node: XmlNode | None) -> _Labels:
    """The labels declared in ``<meta>``, in their file order (stable custom class ids)."""
    labels = _Labels()
    if meta_node is not None:
        for holder in meta_node.children:
            for lab_list in holder.find_all("labels"):
                for lab in lab_list.find_all("label"):
                    nm = lab.find("name")
                    if nm is not None and nm.text:
                        labels.class_of(nm.text)
    return labels


def _read_track(node: XmlNode, name: str, labels: _Labels, rows: "_Rows") -> int:
    """The boxes of one ``<track>`` (``outside`` ones skipped); returns the non-box shapes."""
    tid = xml_int(node, "id", name)
    if "label" not in node.attrib:
        raise InputError(f"{node.where(name)}: track without a 'label' attribute")
    cls = labels.class_of(node.attrib["label"])
    seen: set[int] = set()
    skipped = 0
    for b in node.children:
        if b.tag != "box":
            skipped += 1
            continue
        frame = xml_int(b, "frame", name, lo=0)
        if _flag(b, "outside", name):
            continue
        if frame in seen:
            raise InputError(f"{b.where(name)}: track id={tid} has two boxes in frame {frame}")
        seen.add(frame)
        box = _xyxy(b, name)
        rows.add(frame + 1, tid, box, cls, 0.0 if _flag(b, "occluded", name) else 1.0)
    return skipped


def _read_image(node: XmlNode, name: str, labels: _Labels, rows: "_Rows") -> int:
    """The boxes of one ``<image>`` as anonymous rows (id -1); returns the non-box shapes."""
    frame = xml_int(node, "id", name, lo=0)
    skipped = 0
    for b in node.children:
        if b.tag != "box":
            skipped += 1
            continue
        if "label" not in b.attrib:
            raise InputError(f"{b.where(name)}: box without a 'label' attribute")
        box = _xyxy(b, name)
        cls = labels.class_of(b.attrib["label"])
        rows.add(frame + 1, -1, box, cls, 0.0 if _flag(b, "occluded", name) else 1.0)
    return skipped


class _Rows:
    """Columns of the boxes read so far."""

    def __init__(self) -> None:
        self.frames: list[int] = []
        self.ids: list[int] = []
        self.boxes: list[tuple[float, float, float, float]] = []
        self.classes: list[int] = []
        self.vis: list[float] = []

    def add(self, frame: int, tid: int, box: tuple[float, float, float, float], cls: int,
            vis: float) -> None:
        self.frames.append(frame)
        self.ids.append(tid)
        self.boxes.append(box)
        self.classes.append(cls)
        self.vis.append(vis)

    def annotations(self, meta: dict) -> Annotations:
        if not self.frames:
            return Annotations.empty(meta)
        return Annotations.from_columns(self.frames, self.ids,
                                        np.asarray(self.boxes, dtype=np.float64),
                                        classes=self.classes, visibility=self.vis, meta=meta)


def _num(v: float) -> str:
    return f"{float(v):.12g}"


def _label_names(ann: Annotations) -> dict[int, str]:
    names = {int(k): str(v) for k, v in dict(ann.meta.get("labels", {}) or {}).items()}
    out = {}
    for c in np.unique(ann.classes):
        c = int(c)
        out[c] = names.get(c) or MOT_CLASSES.get(c) or ("object" if c < 0 else f"class{c}")
    return out


def format_cvat(ann: Annotations) -> str:
    """CVAT for video 1.1 text for ``ann``.

    One ``<track>`` per id (rows with id < 0 each become their own one-box track with a fresh id);
    every box is written as a keyframe; a gap in a track and the end of a track before the last
    frame are closed with an ``outside="1"`` box, as CVAT does. The label of a track is the class
    of its first row.
    """
    if len(ann) and ann.frames.min() < 1:
        raise InputError(f"cannot write CVAT: frame numbers must be >= 1, got "
                         f"{int(ann.frames.min())}")
    names = _label_names(ann)
    last = int(ann.frames.max()) - 1 if len(ann) else 0
    out = _meta_xml(ann, names, last)
    for tid, rows in _tracks(ann):
        out += _track_xml(ann, tid, rows, names[int(ann.classes[rows[0]])], last)
    out.append("</annotations>\n")
    return "".join(out)


def _meta_xml(ann: Annotations, names: dict[int, str], last: int) -> list[str]:
    """From the XML declaration to the end of ``<meta>``: the task's frames and labels."""
    out = ['<?xml version="1.0" encoding="utf-8"?>\n<annotations>\n  <version>1.1</version>\n',
           "  <meta>\n    <task>\n", f"      <size>{last + 1 if len(ann) else 0}</size>\n",
           "      <mode>interpolation</mode>\n      <overlap>0</overlap>\n",
           f"      <start_frame>0</start_frame>\n      <stop_frame>{last}</stop_frame>\n",
           "      <labels>\n"]
    for c in sorted(names):
        out.append(f"        <label>\n          <name>{escape(names[c])}</name>\n"
                   f"          <attributes>\n          </attributes>\n        </label>\n")
    out.append("      </labels>\n    </task>\n  </meta>\n")
    return out


def _tracks(ann: Annotations) -> list[tuple[int, np.ndarray]]:
    """``(track id, rows by frame)`` per id, ascending; each row with id < 0 is a track of its
    own with a fresh id above the others."""
    if not len(ann):
        return []
    order = np.lexsort((ann.frames, ann.ids))
    ids, frames = ann.ids[order], ann.frames[order]
    cuts = np.flatnonzero(np.diff(ids)) + 1
    next_id = int(max(ids.max(), -1)) + 1
    tracks: list[tuple[int, np.ndarray]] = []
    for seg in np.split(np.arange(len(order)), cuts):
        tid = int(ids[seg[0]])
        if tid < 0:
            for r in seg:
                tracks.append((next_id, order[[r]]))
                next_id += 1
            continue
        if np.any(np.diff(frames[seg]) == 0):
            dup = int(frames[seg][np.flatnonzero(np.diff(frames[seg]) == 0)[0]])
            raise InputError(f"cannot write CVAT: id {tid} has two boxes in frame {dup}")
        tracks.append((tid, order[seg]))
    return tracks


def _track_xml(ann: Annotations, tid: int, rows: np.ndarray, label: str, last: int) -> list[str]:
    """One ``<track>``: a keyframe per row, an ``outside`` box after a gap or an early end."""
    out = [f'  <track id="{tid}" label={quoteattr(label)} source="manual">\n']
    for k, r in enumerate(rows):
        out.append(_box_xml(ann, r, int(ann.frames[r]) - 1, outside=False))
        f0 = int(ann.frames[r]) - 1
        nxt = int(ann.frames[rows[k + 1]]) - 1 if k + 1 < len(rows) else None
        if (nxt is not None and nxt > f0 + 1) or (nxt is None and f0 < last):
            out.append(_box_xml(ann, r, f0 + 1, outside=True))
    out.append("  </track>\n")
    return out


def _box_xml(ann: Annotations, r: int, frame: int, outside: bool) -> str:
    x, y, w, h = ann.boxes[r]
    v = ann.visibility[r]
    occluded = int(0 <= v < 0.5)
    return (f'    <box frame="{frame}" outside="{int(outside)}" occluded="{occluded}" keyframe="1" '
            f'xtl="{_num(x)}" ytl="{_num(y)}" xbr="{_num(x + w)}" ybr="{_num(y + h)}" '
            f'z_order="0">\n    </box>\n')


def write_cvat(ann: Annotations, path: str | Path) -> None:
    """Write ``ann`` as CVAT for video 1.1 (atomically); see :func:`format_cvat`."""
    text = format_cvat(ann)
    with atomic_open(path) as fh:
        fh.write(text)
