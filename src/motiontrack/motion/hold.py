"""The hold: people and objects that stop stay in an OpenCV subtractor's mask.

OpenCV's KNN learns whatever stands still into its background within a couple of seconds, so a
person who stops vanishes from the mask and from the tracks. The hold leaves the subtractor as it
is (its mask of everything that moves is unchanged) and keeps a background image of its own that
does not learn under the boxes of tracked objects (the selective update of the Reading People
Tracker's background maintenance, kept beside the subtractor rather than inside it). Each frame,
inside the boxes the pipeline passes as ``protect`` (confirmed tracks that have travelled at least
half their height and have slowed down, ``motion.knn.hold_speed``, and the static objects of a
dual background that a track brought):

1. **Held pixels.** A pixel the subtractor calls background (not a shadow either) where the frame
   differs from the hold's background by more than ``threshold`` levels (largest colour channel)
   is foreground: the object the subtractor learnt is still there.
2. **Bounded time.** A pixel that has differed under a box for ``accept_s`` seconds in a row is
   learnt into the hold's background at once (a parked car becomes background after that long).
3. **Ghost pixels.** A pixel held in a frame is remembered; while the subtractor calls it
   foreground, it is taken out of the mask where the frame matches the hold's background again
   and no box covers it: the held object left, and the subtractor, which had learnt it, shows a
   ghost of it there. Under a box such a pixel may be a neighbour's that looks like the ground,
   and is left to the subtractor. A pixel is forgotten when the subtractor calls it background.

Outside the boxes the hold's background learns, every :attr:`Hold.EVERY` frames, where the
subtractor calls a pixel background, so it follows the light and whatever the subtractor accepts;
the ghost filter's ghost pixels (``relearn``) off the boxes are learnt at once (uncovered ground).
Something that stops without a track is not held and fades as the subtractor learns it.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..imaging import largest_difference

__all__ = ["Hold"]

#: subtractor output at and above which a pixel is foreground (MOG2/KNN: 255; shadows 127)
_FOREGROUND = 200


class Hold:
    """Keeps stopped tracked objects in a subtractor's mask (see the module notes).

    Parameters
    ----------
    threshold : int
        Difference from the hold's background (levels, largest colour channel) that makes a pixel
        under a box foreground.
    accept_s : float
        Seconds a pixel under a box may differ from the hold's background before it is learnt
        (0 = never).
    fps : float
        Frames per second of the source (for ``accept_s``).
    """

    #: the background learns every this many frames (it only has to follow slow changes)
    EVERY = 4
    #: weight of the frame at each of those updates (about 20 frames' time constant)
    RATE = 0.2

    def __init__(self, threshold: int = 30, accept_s: float = 180.0, fps: float = 25.0) -> None:
        self.threshold = int(threshold)
        self.accept_s = float(accept_s)
        self.fps = float(fps)
        self.reset()

    def reset(self) -> None:
        """Forget the background: the next frame starts it."""
        self._bg: np.ndarray | None = None     # uint8, the frame's shape
        self._count: np.ndarray | None = None  # frames each pixel has differed under a box
        self._seen: np.ndarray | None = None   # 255 where a pixel was held and still is foreground
        self._frames = 0
        #: the pixels held in the last frame (uint8 0/255), or None when none was
        self.held: np.ndarray | None = None

    @property
    def accept_frames(self) -> int:
        """``accept_s`` in frames (at least 1), or 0 for never; counts stop at 65535."""
        if self.accept_s <= 0:
            return 0
        return min(65535, max(1, int(round(self.accept_s * self.fps))))

    def apply(self, image: np.ndarray, raw: np.ndarray, protect: np.ndarray | None,
              relearn: np.ndarray | None = None) -> np.ndarray:
        """The mask of ``image`` (0/255 uint8): the subtractor's ``raw`` output (255
        foreground, 127 shadow) with held pixels added and ghost pixels taken out; ``protect``
        (bool (h, w) or None): the boxes; ``relearn`` (bool (h, w) or None): pixels the hold's
        background takes from this frame at once."""
        fg = cv2.threshold(raw, _FOREGROUND, 255, cv2.THRESH_BINARY)[1]
        self.held = None
        if self._bg is None or self._bg.shape != image.shape:
            self._bg = image.copy()
            self._count = np.zeros(image.shape[:2], np.uint16)
            self._seen = np.zeros(image.shape[:2], np.uint8)
            self._frames = 1
            return fg
        self._frames += 1
        boxes = None   # 0/1 uint8: OpenCV takes any non-zero value as set
        if protect is not None:
            boxes = np.ascontiguousarray(protect).view(np.uint8)
            if not cv2.countNonZero(boxes):
                boxes = None
        off = cv2.compare(boxes, 0, cv2.CMP_EQ) if boxes is not None else None
        if isinstance(relearn, np.ndarray):
            self._relearn(image, relearn, off)
        out = fg
        if boxes is not None or cv2.countNonZero(self._seen):
            out = self._hold(image, raw, fg, boxes)
        elif self._count.any():
            self._count.fill(0)
        if self._frames % self.EVERY == 0:
            self._learn(image, raw, off)
        return out

    def _relearn(self, image: np.ndarray, relearn: np.ndarray, off: np.ndarray | None) -> None:
        """The ghost filter's ghost pixels (bool (h, w)) off the boxes (``off``: 255 there, or
        None for everywhere) are uncovered ground: the background takes them from ``image``.
        Under a box they are left alone (a bag of the ground's brightness is taken for ground by
        the gray tests of the ghost filter)."""
        where = np.ascontiguousarray(relearn).view(np.uint8)
        if off is not None:
            where = cv2.bitwise_and(where, off)
        if not cv2.countNonZero(where):
            return
        cv2.copyTo(image, where, self._bg)
        keep = cv2.compare(where, 0, cv2.CMP_EQ)
        self._count = cv2.bitwise_and(self._count, self._count, mask=keep)
        self._seen = cv2.bitwise_and(self._seen, keep)

    def _hold(self, image: np.ndarray, raw: np.ndarray, fg: np.ndarray,
              boxes: np.ndarray | None) -> np.ndarray:
        """Steps 1-3 of the module notes, inside the window of the boxes and remembered pixels."""
        where = self._seen if boxes is None else cv2.bitwise_or(boxes, self._seen)
        x, y, w, h = cv2.boundingRect(where)
        win = (slice(y, y + h), slice(x, x + w))
        d = largest_difference(image[win], self._bg[win])
        differs = d > self.threshold
        inside = boxes[win] > 0 if boxes is not None else np.zeros(d.shape, bool)
        cover = differs & inside
        # frames in a row each pixel has differed under a box (0 elsewhere, also off the window)
        count = self._count[win] + cover
        count[~cover] = 0
        limit = self.accept_frames
        if limit and count.max() >= limit:
            due = count >= limit
            self._bg[win][due] = image[win][due]
            count[due] = 0
            cover &= ~due
        self._count.fill(0)
        self._count[win] = count
        held = cover & (raw[win] == 0)
        moving = fg[win] > 0
        ghost = (self._seen[win] > 0) & moving & ~differs & ~inside   # step 3: off the boxes
        out = fg.copy()
        out[win][held] = 255
        out[win][ghost] = 0
        if held.any():
            self.held = np.zeros_like(fg)
            self.held[win][held] = 255
        seen = np.zeros_like(self._seen)
        seen[win] = ((moving & (self._seen[win] > 0)) | held).view(np.uint8) * np.uint8(255)
        self._seen = seen
        return out

    def reseed(self, image: np.ndarray, keep: np.ndarray | None = None) -> None:
        """``image`` becomes the background except at the pixels held or remembered and at
        ``keep`` (the foreground of the last frame: a person who walked in and stopped is in
        ``image``, and the background known behind them is what keeps them held)."""
        if self._bg is None or self._bg.shape != image.shape:
            return
        keep = (self._seen > 0) if keep is None else (keep | (self._seen > 0))
        bg = image.copy()
        bg[keep] = self._bg[keep]
        self._bg = bg

    def background(self, model: np.ndarray) -> np.ndarray:
        """The subtractor's background image ``model`` with the hold's background where a pixel
        is held or remembered: what is behind a stopped object there, not the object."""
        if self._bg is None or self._bg.shape != model.shape or not cv2.countNonZero(self._seen):
            return model
        out = model.copy()
        cv2.copyTo(self._bg, self._seen, out)
        return out

    def _learn(self, image: np.ndarray, raw: np.ndarray, off: np.ndarray | None) -> None:
        """The background learns the frame where the subtractor calls it background, off the
        boxes (``off``: 255 there, or None for everywhere) and the remembered pixels."""
        learn = cv2.compare(raw, 0, cv2.CMP_EQ)
        if off is not None:
            learn = cv2.bitwise_and(learn, off)
        learn = cv2.bitwise_and(learn, cv2.bitwise_not(self._seen))
        blended = cv2.addWeighted(self._bg, 1.0 - self.RATE, image, self.RATE, 0.0)
        cv2.copyTo(blended, learn, self._bg)
