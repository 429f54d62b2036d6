"""Output writers of scene analytics: ``events.jsonl`` and ``counts.csv``.

Both are writers of a :class:`~motiontrack.run.job.Job` reading the
:class:`~motiontrack.types.SceneFrame` of each frame (``FrameResult.scene``): the job of
``track --scene`` and that of ``analyze`` (:mod:`motiontrack.run.analyze`), so both commands
write the same files the same way.
"""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..classify import CLASS_NAMES
from ..errors import ConfigError
from ..io.atomic import AtomicFile
from ..types import FrameResult, SceneFrame, events_header
from .folder import RunFolder
from .job import JobContext, Writer

__all__ = ["EventsWriter", "CountsWriter"]


class EventsWriter(Writer):
    """``events.jsonl``: a header object (schema, version, fps, source, scene), then one JSON
    object per event in frame order (``docs/analytics.md``); a frame after a discontinuity of
    the source is preceded by its ``{"type": "discontinuity", "reason", "frame"}`` record."""

    def __init__(self, out: Path, source: str = "", scene: str = "") -> None:
        self.paths = {"events": RunFolder(out).events}
        self.source, self.scene = str(source), str(scene)
        self.count = 0
        self._file: AtomicFile | None = None

    def start(self, ctx: JobContext) -> None:
        self._file = AtomicFile(self.paths["events"])
        self._file.write(json.dumps(events_header(ctx.fps, self.source, self.scene)) + "\n")

    def write(self, result: FrameResult) -> None:
        frame = result.scene
        if frame is not None and frame.discontinuity is not None:
            self._file.write(json.dumps(frame.discontinuity.to_json(frame.frame)) + "\n")
        if frame is not None and frame.events:
            self._file.write("".join(json.dumps(e.to_json()) + "\n" for e in frame.events))
            self.count += len(frame.events)

    def close(self, keep: bool) -> None:
        if self._file is not None:
            self._file.commit() if keep else self._file.discard()
            self._file = None


class CountsWriter(Writer):
    """``counts.csv``: one row per time bin of ``bin_s`` seconds (bin ``k`` holds the frames
    with ``k * bin_s <= t < (k + 1) * bin_s``): its frames, each line's ``in`` and ``out``
    crossings in the bin, each zone's mean and peak occupancy over the bin's frames.

    Columns: ``bin, start_s, end_s, frames``, then ``line:NAME:in``, ``line:NAME:out`` per line
    and ``zone:NAME:mean``, ``zone:NAME:peak`` per zone, in the scene's order; ``by_class``
    adds ``line:NAME:CLASS:in``, ``line:NAME:CLASS:out`` for each line and class
    (:data:`~motiontrack.classify.CLASS_NAMES`, by the events' ``label``).
    """

    def __init__(self, out: Path, lines: Sequence[Any], zones: Sequence[Any],
                 bin_s: float = 60.0, by_class: bool = False) -> None:
        if not (math.isfinite(bin_s) and bin_s > 0):
            raise ConfigError(f"--bin-s must be > 0 seconds, got {bin_s!r}")
        self.paths = {"counts": RunFolder(out).counts}
        self.lines = [ln.name for ln in lines]
        self.zones = [z.name for z in zones]
        self.bin_s = float(bin_s)
        self.classes = CLASS_NAMES if by_class else ()
        self._file: AtomicFile | None = None
        self._fps = 25.0
        self._bin: int | None = None

    def start(self, ctx: JobContext) -> None:
        self._fps = float(ctx.fps)
        self._file = AtomicFile(self.paths["counts"])
        head = ["bin", "start_s", "end_s", "frames"]
        head += [f"line:{n}:{d}" for n in self.lines for d in ("in", "out")]
        head += [f"zone:{n}:{s}" for n in self.zones for s in ("mean", "peak")]
        head += [f"line:{n}:{c}:{d}" for n in self.lines for c in self.classes
                 for d in ("in", "out")]
        self._file.write(self._row(head))

    def write(self, result: FrameResult) -> None:
        if result.scene is not None:
            self._add(result.scene)

    def _add(self, frame: SceneFrame) -> None:
        # a little slack so that t = k * bin_s computed in floating point lands in bin k
        b = int(math.floor((frame.frame - 1) / self._fps / self.bin_s + 1e-9))
        if b != self._bin:
            self._flush()
            self._bin, self._frames = b, 0
            self._in = np.zeros(len(self.lines), dtype=np.int64)
            self._out = np.zeros(len(self.lines), dtype=np.int64)
            self._sum = np.zeros(len(self.zones), dtype=np.int64)
            self._peak = np.zeros(len(self.zones), dtype=np.int64)
            self._by_class = np.zeros((len(self.lines), len(self.classes), 2), dtype=np.int64)
        self._frames += 1
        for e in frame.events:
            if e.type == "line_cross" and e.line in self.lines:
                j, k = self.lines.index(e.line), 0 if e.direction == "in" else 1
                (self._in if k == 0 else self._out)[j] += 1
                if e.label in self.classes:
                    self._by_class[j, self.classes.index(e.label), k] += 1
        occ = np.array([frame.occupancy.get(n, 0) for n in self.zones], dtype=np.int64)
        self._sum += occ
        self._peak = np.maximum(self._peak, occ)

    def _flush(self) -> None:
        if self._bin is None or self._frames == 0:
            return
        row: list = [self._bin, round(self._bin * self.bin_s, 6),
                     round((self._bin + 1) * self.bin_s, 6), self._frames]
        for i in range(len(self.lines)):
            row += [int(self._in[i]), int(self._out[i])]
        for k in range(len(self.zones)):
            row += [round(float(self._sum[k]) / self._frames, 4), int(self._peak[k])]
        row += [int(v) for v in self._by_class.reshape(-1)]
        self._file.write(self._row(row))
        self._bin = None

    @staticmethod
    def _row(values: list) -> str:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(values)
        return buf.getvalue()

    def close(self, keep: bool) -> None:
        if self._file is not None:
            if keep:
                self._flush()
                self._file.commit()
            else:
                self._file.discard()
            self._file = None
