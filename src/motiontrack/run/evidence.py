"""The snapshot and clip of each event, written beside the run's outputs in ``evidence/``.

For event ``ID`` (its id in the event store): ``ID.jpg``, the annotated frame of the event;
``ID-object.jpg``, the object's box (with a margin of a quarter of its size, at least 16 px) cut
from the same frame; and a Motion-JPEG clip from ``clip_s[0]`` seconds before the event to
``clip_s[1]`` after it (the scene's ``[evidence]``, :mod:`motiontrack.analytics.evidence`).

Events whose clips overlap share one: a clip still being gathered takes in the next event's
seconds (up to :data:`MAX_CLIP_S` in all), so a busy scene writes its video once rather than once
per event. The clip is named after its first event (``ID.avi``); the store records for each
event the clip and where the event's own seconds start in it (``clip_offset``).

The pre-roll comes from a ring buffer of the annotated frames, JPEG-encoded once as they pass
(at most ``clip_fps`` a second, at most ``clip_width`` pixels across), so an event costs no
encoding of the past; a clip's file is written as its frames pass (the ring's pre-roll first),
so the frames of the clips being gathered are on disk, not in memory, and it is complete once
its last frame has passed, or when the run ends (then it ends there). Clips are written under a
temporary name and renamed: a killed run leaves each clip complete and recorded in the store,
or not recorded (its ``.part`` file is removed by the next run of the folder).
"""

from __future__ import annotations

import collections
import logging
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import cv2
import numpy as np

from ..analytics.evidence import EvidencePlan
from ..io.atomic import DiskFullError, atomic_write_bytes
from ..io.clips import ClipWriter
from ..types import FrameResult

log = logging.getLogger(__name__)

__all__ = ["EvidenceKeeper", "EVIDENCE_DIR"]

EVIDENCE_DIR = "evidence"
JPEG_QUALITY = 85
#: the clips' frames: many of them, each seen for a fraction of a second
CLIP_QUALITY = 75
#: smallest margin around an object's box in its crop (pixels)
MIN_MARGIN = 16
#: the files of evidence/ this module writes
_OURS = re.compile(r"\d+(\.jpg|-object\.jpg|\.avi)|\.\d+(-object)?\..*\.part\.(avi|jpg)")


#: the longest clip shared by events whose seconds overlap (then a new clip starts)
MAX_CLIP_S = 60.0


@dataclass
class _Clip:
    """A clip being gathered: its file, written from frame number ``first`` up to ``last``,
    and its events with the frame their own seconds start at."""

    event_id: int
    writer: ClipWriter
    first: int
    last: int
    members: list[tuple[int, int]] = field(default_factory=list)
    done: bool = False


class EvidenceKeeper:
    """Snapshots and clips of one run's events in ``folder/evidence/``; paths are given
    relative to ``root`` (the event store's folder)."""

    def __init__(self, folder: Path, root: Path, plan: EvidencePlan, fps: float) -> None:
        self.dir = Path(folder) / EVIDENCE_DIR
        self.root = Path(root)
        self.plan = plan
        self.fps = float(fps) or 25.0
        spec = plan.default
        self.step = max(1, round(self.fps / spec.clip_fps))   # keep every step-th frame
        self.clip_fps = self.fps / self.step
        self.width = spec.clip_width
        self.any_clip = spec.clip or any(o.clip_s is not None and (o.clip_s[0] or o.clip_s[1])
                                         for _, _, o in plan.overrides)
        before = int(np.ceil(plan.longest_before_s * self.clip_fps)) + 1
        self._ring: collections.deque = collections.deque(maxlen=before)
        self._open: list[_Clip] = []

    def clear(self) -> int:
        """Remove the snapshots and clips an earlier run left in ``evidence/`` (by their names:
        ``ID.jpg``, ``ID-object.jpg``, ``ID.avi`` and unfinished ``.part`` clips), before a run
        whose store starts afresh numbers its events from 1 again; how many were removed."""
        if not self.dir.is_dir():
            return 0
        n = 0
        for p in self.dir.iterdir():
            if p.is_file() and _OURS.fullmatch(p.name):
                p.unlink()
                n += 1
        return n

    def _rel(self, path: Path) -> str:
        return path.relative_to(self.root).as_posix() if path.is_relative_to(self.root) \
            else str(path)

    def frame(self, frame: int, picture: np.ndarray | None) -> list[tuple[int, str, float]]:
        """Pass frame ``frame`` (its annotated picture; None when no clip wants it); the events
        whose clips are complete now, ``(event id, path, seconds into the clip where the
        event's own seconds start)``."""
        if not self.any_clip or picture is None or frame % self.step:
            return self._finished(frame)
        jpeg = self._clip_jpeg(picture)
        self._ring.append((frame, jpeg))
        for clip in self._open:
            if frame <= clip.last:
                self._add(clip, jpeg)
        return self._finished(frame)

    def _add(self, clip: _Clip, jpeg: bytes) -> None:
        """Write a frame of ``clip``; a device that fails (full) drops the clip."""
        if clip.done:
            return
        try:
            clip.writer.add(jpeg)
        except (OSError, DiskFullError) as exc:
            log.warning("clip of event %d not written: %s", clip.event_id, exc)
            clip.writer.abort()
            clip.done = True

    def snapshots(self, event: Mapping[str, Any]) -> bool:
        """Whether ``event``'s rule keeps a snapshot."""
        return self.plan.of(event).snapshot

    def needs_picture(self, frame: int) -> bool:
        """Whether :meth:`frame` will use the picture of ``frame`` (draw it only then)."""
        return self.any_clip and frame % self.step == 0

    def event(self, event_id: int, event: Mapping[str, Any], result: FrameResult,
              picture: np.ndarray | None) -> str | None:
        """Write the snapshots of ``event`` (if its rule keeps them) and start its clip; the
        snapshot's path, or None."""
        spec = self.plan.of(event)
        frame = int(event.get("frame", 0))
        if spec.clip:
            self._clip(event_id, frame - spec.clip_s[0] * self.fps,
                       frame + int(spec.clip_s[1] * self.fps))
        if not spec.snapshot or picture is None:
            return None
        path = self.dir / f"{event_id}.jpg"
        crop = _crop(result.frame, _box_of(event, result))
        try:
            self.dir.mkdir(parents=True, exist_ok=True)
            _write_jpeg(path, picture)
            if crop is not None:
                _write_jpeg(self.dir / f"{event_id}-object.jpg", crop)
        except (OSError, DiskFullError) as exc:   # a full device: no snapshot, the event stays
            log.warning("snapshot of event %d not written: %s", event_id, exc)
            return None
        return self._rel(path)

    def _clip(self, event_id: int, start: float, end: int) -> None:
        """Gather frames ``start``..``end`` for ``event_id``: in the newest clip when it is
        still open there and stays within :data:`MAX_CLIP_S`, else in a new one from the ring."""
        newest = self._open[-1] if self._open else None
        longest = int(MAX_CLIP_S * self.fps)
        if newest is not None and start <= newest.last + 1 and end - newest.first <= longest:
            newest.last = max(newest.last, end)
            newest.members.append((event_id, max(newest.first, int(np.ceil(start)))))
            return
        kept = [(f, j) for f, j in self._ring if f >= start]
        first = kept[0][0] if kept else int(np.ceil(start))
        clip = _Clip(event_id, ClipWriter(self.dir / f"{event_id}.avi", self.clip_fps), first,
                     end)
        clip.members.append((event_id, first))
        self._open.append(clip)
        for _, jpeg in kept:
            self._add(clip, jpeg)

    def _finished(self, frame: int | None) -> list[tuple[int, str, float]]:
        out = []
        for clip in self._open:
            if clip.done or not (frame is None or frame >= clip.last):
                continue
            clip.done = True
            if not clip.writer.frames:
                continue
            try:
                path = clip.writer.close()
            except (OSError, DiskFullError) as exc:   # a full device: no clip
                log.warning("clip of event %d not written: %s", clip.event_id, exc)
                continue
            rel = self._rel(path)
            out += [(event_id, rel, round((start - clip.first) / self.fps, 3))
                    for event_id, start in clip.members]
        self._open = [c for c in self._open if not c.done]
        return out

    def close(self) -> list[tuple[int, str, float]]:
        """The run ended: write the clips still open, ending where the run ended."""
        return self._finished(None)

    def _clip_jpeg(self, picture: np.ndarray) -> bytes:
        h, w = picture.shape[:2]
        if w > self.width:
            picture = cv2.resize(picture, (self.width, max(1, round(h * self.width / w))),
                                 interpolation=cv2.INTER_LINEAR)
        ok, jpeg = cv2.imencode(".jpg", picture, [cv2.IMWRITE_JPEG_QUALITY, CLIP_QUALITY])
        return jpeg.tobytes()


def _write_jpeg(path: Path, picture: np.ndarray) -> None:
    """Write ``picture`` whole or not at all (``cv2.imwrite`` fails without saying why)."""
    ok, jpeg = cv2.imencode(".jpg", picture, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
    if not ok:
        raise OSError(f"cannot encode {path.name}")
    atomic_write_bytes(path, jpeg.tobytes())


def _box_of(event: Mapping[str, Any], result: FrameResult) -> tuple[float, float, float, float]:
    """The box of the event's track in this frame, or a square around its point (an object
    that is no track any more, such as an abandoned bag)."""
    for t in result.tracks:
        if t.id == event.get("track"):
            return t.box.x, t.box.y, t.box.w, t.box.h
    x, y, side = float(event.get("x", 0.0)), float(event.get("y", 0.0)), 64.0
    return x - side / 2, y - side, side, side


def _crop(image: np.ndarray | None, box: tuple[float, float, float, float]) -> np.ndarray | None:
    if image is None or not image.size:
        return None
    x, y, w, h = box
    m = max(MIN_MARGIN, 0.25 * max(w, h))
    H, W = image.shape[:2]
    x0, y0 = max(0, int(x - m)), max(0, int(y - m))
    x1, y1 = min(W, int(np.ceil(x + w + m))), min(H, int(np.ceil(y + h + m)))
    return image[y0:y1, x0:x1] if x1 > x0 and y1 > y0 else None
