"""``heatmap.png`` and ``heatmap_world.png``: where tracks spent time.

One writer of a :class:`~motiontrack.run.job.Job` for ``track --scene`` (each frame's reported
tracks, the motion detector's background when the run ends) and ``analyze`` (each frame's rows
of the tracks file, with a background it is given or none).

Every frame, each reported track counts one visit at its anchor (the scene's ``anchor``) in
the pixel under it, and with a camera at its foot point on the ground in 5 cm cells. The
pictures smooth the visits with a Gaussian (σ = 1 % of the frame's larger side, at least
2 px; 0.2 m on the ground) and colour them over the background, and over a ground-plane grid
with metre ticks (``X`` right, ``Y`` up) whose extent is the tracks' own plus a metre, rounded
out to whole metres.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Callable, Sequence

import cv2
import numpy as np

from ..analytics.heatmap import HeatGrid, WorldHeat, anchor_points, world_extent
from ..calibrate.measure import world_positions
from ..errors import MotionTrackError
from ..io.atomic import atomic_write_bytes
from ..io.sources import open_source
from ..render.heatmap import heat_overlay, world_heat_map
from ..types import FrameResult
from .folder import RunFolder
from .job import JobContext, JobSummary, Writer

log = logging.getLogger(__name__)

__all__ = ["HeatmapWriter", "median_background", "scene_geometry", "WORLD_CELL_M",
           "WORLD_SIGMA_M"]

#: ground cells the world map counts visits in
WORLD_CELL_M = 0.05
#: smoothing of the world map
WORLD_SIGMA_M = 0.2
#: the world map's larger side is about this many pixels (5 to 50 px per metre)
_WORLD_SIDE_PX = 800


def image_sigma_px(width: int, height: int) -> float:
    """The image map's smoothing: 1 % of the frame's larger side, at least 2 pixels."""
    return max(2.0, 0.01 * max(width, height))


def median_background(video: Any, samples: int = 25) -> np.ndarray:
    """The per-pixel median of up to ``samples`` frames spread evenly over ``video`` (anything
    :func:`~motiontrack.io.sources.open_source` opens): people who walk through are gone from
    it, the scene stays."""
    with open_source(video) as src:
        n = src.expected_frames() or 0
        every = max(1, n // samples) if n else 1
        kept: list[np.ndarray] = []
        for k, frame in enumerate(src):
            if k % every == 0:
                kept.append(frame.image)
                if len(kept) >= samples:
                    break
    if not kept:
        raise MotionTrackError(f"{video}: no frames to take a background from")
    return np.median(np.stack(kept), axis=0).astype(np.uint8)


class HeatmapWriter(Writer):
    """The heat maps of a run (see the module docstring).

    Parameters
    ----------
    out : the output folder.
    anchor : the scene's anchor (``bottom_center`` | ``center``).
    size : ``(width, height)`` of the image map; ``None``: the source's.
    camera : a calibrated camera fitted to the frames: also ``heatmap_world.png``.
    background : the picture under the image map (any size, gray or BGR), or a function
        returning it when the run ends; ``None`` in a job: the motion detector's background,
        else the last frame.
    geometry : pixel polylines drawn over the maps (the scene's lines and closed zones).
    boxes_of : the boxes a frame's result counts, (N, 4) ``x, y, w, h``; default: its tracks'.
    label : count only the tracks of this class (``--by-class``): the map is
        ``heatmap_LABEL.png`` (no world map), its ``summary.json`` entry ``heatmap_LABEL``;
        ``boxes_of`` then gets the class too.
    """

    def __init__(self, out: Path, anchor: str = "bottom_center",
                 size: tuple[int, int] | None = None, camera: Any = None,
                 background: np.ndarray | Callable[[], np.ndarray | None] | None = None,
                 geometry: Sequence[np.ndarray] = (),
                 boxes_of: Callable[..., Any] | None = None, label: str | None = None) -> None:
        folder = RunFolder(out)
        self.key = "heatmap" if label is None else f"heatmap_{label}"
        self.paths = {self.key: folder.heatmap if label is None else folder.heatmap_of(label)}
        self.label = label
        if label is not None:
            camera = None
        if camera is not None:
            self.paths["heatmap_world"] = folder.heatmap_world
        self.anchor, self.size, self.camera = anchor, size, camera
        self.background = background
        self.boxes_of = boxes_of or _track_boxes
        self.geometry = [np.asarray(g, dtype=np.float64).reshape(-1, 2) for g in geometry]
        self.grid: HeatGrid | None = None
        self.world = WorldHeat(WORLD_CELL_M) if camera is not None else None
        self.info: dict[str, Any] = {}
        self._ctx: JobContext | None = None
        self._last: np.ndarray | None = None

    def start(self, ctx: JobContext) -> None:
        self._ctx = ctx
        w, h = self.size or (ctx.info.width, ctx.info.height)
        self.grid = HeatGrid(int(w), int(h))

    def write(self, result: FrameResult) -> None:
        boxes = self.boxes_of(result) if self.label is None else self.boxes_of(result, self.label)
        b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
        if result.frame is not None and result.frame.size:   # a source without pictures: black
            self._last = result.frame
        if not len(b):
            return
        self.grid.add(anchor_points(b, self.anchor))
        if self.world is not None:
            self.world.add(world_positions(b, self.camera))

    def finish(self, summary: JobSummary) -> None:
        summary.extra[self.key] = self.info

    def close(self, keep: bool) -> None:
        if not keep or self.grid is None:
            return
        g = self.grid
        bg, kind = self._background()
        sigma = image_sigma_px(g.width, g.height)
        img = heat_overlay(g.counts, bg, sigma, self.geometry)
        self._save(self.paths[self.key], img)
        self.info = {"visits": g.visits, "outside": g.outside, "width": g.width,
                     "height": g.height, "sigma_px": round(sigma, 3), "background": kind}
        if self.world is not None:
            centres, visits = self.world.points()
            extent = world_extent(centres)
            span = max(extent[1] - extent[0], extent[3] - extent[2])
            ppm = float(min(50, max(5, _WORLD_SIDE_PX // span)))
            lines = [self._to_world(p) for p in self.geometry]
            self._save(self.paths["heatmap_world"],
                       world_heat_map(centres, visits, extent, ppm, WORLD_SIGMA_M,
                                      lines=[ln for ln in lines if ln is not None]))
            self.info["world"] = {"visits": self.world.visits, "extent_m": list(extent),
                                  "px_per_m": ppm, "cell_m": WORLD_CELL_M,
                                  "sigma_m": WORLD_SIGMA_M}
        self.grid = None

    # ----------------------------------------------------------------------- helpers
    def _background(self) -> tuple[np.ndarray | None, str]:
        """The picture under the image map and what it is (for ``summary.json``)."""
        if self.background is not None:
            bg = self.background() if callable(self.background) else self.background
            return bg, "given" if bg is not None else "none"
        if self._ctx is not None:
            bg = self._ctx.processor.background()
            if bg is not None:
                return bg, "motion background"
        return self._last, "last frame" if self._last is not None else "none"

    def _to_world(self, pixels: np.ndarray) -> np.ndarray | None:
        w = np.asarray(self.camera.image_to_world(pixels), dtype=np.float64).reshape(-1, 2)
        return w if np.all(np.isfinite(w)) else None

    @staticmethod
    def _save(path: Path, img: np.ndarray) -> None:
        ok, buf = cv2.imencode(".png", img)
        if not ok:  # pragma: no cover - PNG encoding of a uint8 image does not fail
            raise MotionTrackError(f"could not encode {path.name}")
        atomic_write_bytes(path, buf.tobytes())


def _track_boxes(result: FrameResult, label: str | None = None) -> np.ndarray:
    """The boxes of a frame's tracks (of class ``label`` when given), (N, 4) ``x, y, w, h``."""
    return np.array([t.box.as_array() for t in result.tracks
                     if label is None or t.label == label], dtype=np.float64).reshape(-1, 4)


def scene_geometry(lines: Sequence[Any], zones: Sequence[Any]) -> list[np.ndarray]:
    """The scene's lines (``a``, ``b``) and zones (``polygon``, closed) as pixel polylines."""
    out = [np.array([ln.a, ln.b], dtype=np.float64) for ln in lines]
    for z in zones:
        poly = np.asarray(z.polygon, dtype=np.float64).reshape(-1, 2)
        out.append(np.vstack([poly, poly[:1]]))
    return out
