"""A synthetic scene seen through a moving camera: a shaking camera or a slow pan, with exact
ground truth.

The scene is rendered ``margin`` pixels larger on every side than the view; each frame is the
``width`` x ``height`` window at that frame's whole-pixel offset into it, so a pan shows new
ground entering the view. Masks and boxes move with the window exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..types import Annotations, Frame
from .scenes import make_scene
from .sequence import SyntheticScene

__all__ = ["MovingCamera", "shake_offsets", "pan_offsets", "shift_annotations"]


def shake_offsets(n_frames: int, amplitude: int, seed: int = 0) -> np.ndarray:
    """(n_frames, 2) int offsets (dx, dy), each uniform in [-amplitude, amplitude] and drawn
    anew every frame (a camera shaking about a fixed position)."""
    rng = np.random.default_rng(seed)
    return rng.integers(-amplitude, amplitude + 1, size=(n_frames, 2))


def pan_offsets(n_frames: int, speed: float, start: int = 0) -> np.ndarray:
    """(n_frames, 2) int offsets of a camera panning right at ``speed`` px per frame from
    ``start`` (rounded to whole pixels; dy = 0)."""
    dx = np.round(start + speed * np.arange(n_frames)).astype(int)
    return np.stack([dx, np.zeros_like(dx)], axis=1)


def shift_annotations(gt: Annotations, offsets: np.ndarray, width: int, height: int,
                      origin: tuple[int, int] = (0, 0)) -> Annotations:
    """``gt`` seen through a window of ``width`` x ``height`` at ``origin + offsets[frame - 1]``
    of each (1-based) frame: boxes moved by minus that, rows whose box lies wholly outside the
    window dropped."""
    k = gt.frames.astype(int) - 1
    shift = offsets[np.clip(k, 0, len(offsets) - 1)] + np.asarray(origin)
    boxes = np.asarray(gt.boxes, float).copy()
    boxes[:, :2] -= shift
    inside = ((boxes[:, 0] + boxes[:, 2] > 0) & (boxes[:, 1] + boxes[:, 3] > 0)
              & (boxes[:, 0] < width) & (boxes[:, 1] < height))
    return Annotations.from_columns(
        frames=gt.frames[inside], ids=gt.ids[inside], boxes=boxes[inside],
        scores=gt.scores[inside], consider=gt.consider[inside], classes=gt.classes[inside],
        visibility=gt.visibility[inside], world=gt.world[inside], meta=dict(gt.meta))


@dataclass(frozen=True)
class MovingCamera:
    """``scene`` (rendered ``margin`` px larger on every side than the view) seen through a
    ``width`` x ``height`` window at ``margin + offsets[i]`` in frame ``i``.

    Build one with :meth:`shaking` or :meth:`panning`."""

    scene: SyntheticScene
    offsets: np.ndarray
    width: int
    height: int
    margin: int

    @classmethod
    def shaking(cls, name: str, amplitude: int, seed: int = 0, width: int = 320,
                height: int = 240, **overrides) -> "MovingCamera":
        """Scene ``name`` with a camera shaking ``amplitude`` px in x and y, every frame."""
        m = int(amplitude)
        scene = make_scene(name, seed, width=width + 2 * m, height=height + 2 * m, **overrides)
        return cls(scene, shake_offsets(scene.n_frames, m, seed), width, height, m)

    @classmethod
    def panning(cls, name: str, speed: float, seed: int = 0, width: int = 320,
                height: int = 240, **overrides) -> "MovingCamera":
        """Scene ``name`` with a camera panning right at ``speed`` px per frame."""
        n = int(overrides.get("n_frames", 0)) or None
        scene = make_scene(name, seed, width=width, height=height, **overrides)
        n = n or scene.n_frames
        travel = int(np.ceil(speed * n)) + 1
        half = (travel + 1) // 2
        scene = make_scene(name, seed, width=width + 2 * half, height=height,
                           **{**overrides, "n_frames": n})
        return cls(scene, pan_offsets(n, speed, start=-half), width, height, half)

    @property
    def n_frames(self) -> int:
        return self.scene.n_frames

    def _window(self, i: int) -> tuple[slice, slice]:
        dx, dy = self.offsets[i]
        x0 = self.margin + int(dx)
        y0 = (self.scene.height - self.height) // 2 + int(dy)
        return slice(y0, y0 + self.height), slice(x0, x0 + self.width)

    def frame(self, i: int) -> np.ndarray:
        """Frame ``i``: (height, width, 3) uint8 BGR."""
        return self.scene.frame(i)[self._window(i)].copy()

    def foreground_mask(self, i: int) -> np.ndarray:
        """Frame ``i``'s exact mask (the scene's labels) in the view."""
        return self.scene.foreground_mask(i)[self._window(i)].copy()

    def ground_truth(self) -> Annotations:
        """The scene's ground truth in the view's coordinates."""
        origin = (self.margin, (self.scene.height - self.height) // 2)
        return shift_annotations(self.scene.ground_truth(), self.offsets, self.width,
                                 self.height, origin)

    def frames(self) -> list[Frame]:
        """Every frame as a :class:`~motiontrack.types.Frame` (25 fps timestamps)."""
        fps = float(self.scene.fps)
        return [Frame(index=i, image=self.frame(i), timestamp=i / fps)
                for i in range(self.n_frames)]
