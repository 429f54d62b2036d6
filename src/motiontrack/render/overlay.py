"""Overlay ground truth and several runs on the video (the thesis' ``overlaybbs`` script).

Each annotation set gets one colour (ground truth green, runs from a fixed palette of well separated
colours) and a legend in the top-left corner names them, so that several parameter settings can be
compared on the same frames. Output: a video through :class:`~motiontrack.io.video.VideoSink`
(WebM VP8 by default) and optionally PNG stills of chosen frames.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Callable, Sequence

import cv2
import numpy as np

from ..errors import ConfigError
from ..io.atomic import atomic_write_bytes
from ..io.sources import open_source
from ..io.video import VideoSink
from ..types import Annotations
from .annotate import draw_label

log = logging.getLogger(__name__)

__all__ = ["GT_COLOR", "PALETTE", "draw_overlay", "render_overlay", "OverlayResult"]

#: BGR
GT_COLOR = (80, 220, 80)
PALETTE = ((60, 60, 255), (255, 150, 40), (0, 215, 255), (255, 60, 220), (255, 255, 80),
           (40, 140, 255), (180, 120, 255), (200, 200, 200))


def _colors(n: int) -> list[tuple[int, int, int]]:
    return [PALETTE[i % len(PALETTE)] for i in range(n)]


def draw_overlay(image: np.ndarray, layers: Sequence[tuple[str, tuple[int, int, int], np.ndarray, np.ndarray]],
                 frame_label: str | None = None, legend: bool = True) -> np.ndarray:
    """Draw boxes of several annotation layers on a copy of ``image``.

    Parameters
    ----------
    image : (h, w, 3) or (h, w) uint8 frame (not modified).
    layers : (name, BGR colour, boxes (N, 4) x,y,w,h px, ids (N,)) per layer; the first layer is
        drawn thicker (ground truth).
    frame_label : text drawn at the bottom-left (e.g. the frame number).
    legend : draw a legend naming the layers in their colours.

    Returns
    -------
    (h, w, 3) uint8
    """
    img = image.copy() if image.ndim == 3 else cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    for li, (name, color, boxes, ids) in enumerate(layers):
        thick = 2 if li == 0 else 1
        for b, i in zip(np.asarray(boxes).reshape(-1, 4), np.asarray(ids).reshape(-1)):
            p1 = (int(round(b[0])), int(round(b[1])))
            p2 = (int(round(b[0] + b[2])), int(round(b[1] + b[3])))
            cv2.rectangle(img, p1, p2, color, thick)
            cv2.putText(img, str(int(i)), (p1[0] + 2, p2[1] - 3), cv2.FONT_HERSHEY_SIMPLEX, 0.35,
                        color, 1, cv2.LINE_AA)
    if legend:
        y = 4
        for name, color, _, _ in layers:
            (tw, th), base = cv2.getTextSize(name, cv2.FONT_HERSHEY_SIMPLEX, 0.5, 1)
            y += th + base + 4
            draw_label(img, name, (6, y), color)
    if frame_label:
        draw_label(img, frame_label, (6, img.shape[0] - 6), (30, 30, 30))
    return img


class OverlayResult:
    def __init__(self, video: str | None, pngs: list[str], frames: int) -> None:
        self.video, self.pngs, self.frames = video, pngs, frames


def render_overlay(source: Any, out: str | Path | None, runs: Sequence[tuple[str, Annotations]],
                   gt: Annotations | None = None, *, frames: tuple[int, int | None] | None = None,
                   png_frames: Sequence[int] = (), png_dir: str | Path | None = None,
                   codec: str = "vp80", progress: Callable[[int], None] | None = None) -> OverlayResult:
    """Render ground truth and runs over ``source``.

    Parameters
    ----------
    source : anything :func:`~motiontrack.io.sources.open_source` accepts.
    out : output video path (None: only PNG stills).
    runs : (legend name, annotations) per run; frames 1-based (MOTChallenge).
    gt : ground truth (drawn first, green); rows with ``consider == False`` are skipped.
    frames : (first, last) 1-based inclusive frame range; ``last`` None = to the end.
    png_frames : 1-based frame numbers also written as ``png_dir/frame_%06d.png``.
    png_dir : folder for the stills (default: next to ``out``).
    """
    if out is None and not png_frames:
        raise ConfigError("nothing to write: give an output video or --png-frames")
    lo, hi = frames if frames is not None else (1, None)
    if lo < 1 or (hi is not None and hi < lo):
        raise ConfigError(f"frame range must satisfy 1 <= first <= last, got {lo}:{hi}")
    start = lo - 1
    src = open_source(source, start, 0 if hi is None else hi - lo + 1)
    layers_src: list[tuple[str, tuple[int, int, int], Annotations]] = []
    if gt is not None:
        layers_src.append(("ground truth", GT_COLOR, gt.select(np.asarray(gt.consider, dtype=bool))))
    for (name, ann), color in zip(runs, _colors(len(runs))):
        layers_src.append((name, color, ann))
    indexed = [(n, c, a, a.by_frame()) for n, c, a in layers_src]
    wanted = set(int(f) for f in png_frames)
    pdir = Path(png_dir) if png_dir is not None else (Path(out).parent if out is not None else Path("."))
    sink = VideoSink(out, src.info.fps or 25.0, codec) if out is not None else None
    pngs: list[str] = []
    n = 0
    try:
        for frame in src:
            f = frame.index + 1
            if f < lo:  # a ready-made Source ignores start/max_frames
                continue
            if hi is not None and f > hi:
                break
            layers = []
            for name, color, ann, idx in indexed:
                rows = idx.get(f)
                if rows is None:
                    layers.append((name, color, np.zeros((0, 4)), np.zeros(0)))
                else:
                    layers.append((name, color, ann.boxes[rows], ann.ids[rows]))
            img = draw_overlay(frame.image, layers, frame_label=f"frame {f}")
            if sink is not None:
                sink.write(img)
            if f in wanted:
                ok, buf = cv2.imencode(".png", img)
                if ok:
                    p = pdir / f"frame_{f:06d}.png"
                    atomic_write_bytes(p, buf.tobytes())
                    pngs.append(str(p))
            n += 1
            if progress is not None:
                progress(1)
    finally:
        src.close()
        if sink is not None:
            sink.close()
    missing = sorted(wanted - {int(Path(p).stem.split("_")[1]) for p in pngs})
    if missing:
        log.warning("--png-frames outside the rendered frames: %s", ", ".join(map(str, missing)))
    return OverlayResult(str(out) if out is not None and n else None, pngs, n)
