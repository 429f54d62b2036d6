"""The motion stage: a motion detector behind camera-motion compensation, with sudden-change
handling.

Each frame (:meth:`MotionStage.apply`):

1. **Compensation** (``stabilize``, :mod:`~motiontrack.motion.stabilize`): the frame is warped
   into the reference frame, so the background model sees a steady scene. When the reference
   moves on (a pan), the model is moved with it: it re-learns from its own background image
   carried into the new reference (:meth:`Stabilizer.to_anchor`), the new view filling what the
   old one did not reach.
2. **Detection**: the detector's mask of the warped frame.
3. **Sudden change** (``motion.relearn_*``): when more than ``relearn_fraction`` of the frame
   turns foreground at once (once the model is 25 frames old), or its mean brightness jumps by more than ``relearn_brightness``
   grey levels, the model re-learns (:meth:`MotionStage.relearn`) from the frame itself,
   except where the previous frame showed motion: there it takes its old background, scaled
   by the change of the mean brightness, so the objects present stand out at once rather than
   being learnt. The frame is then detected again by the new model; the pipeline ignores the
   regions of ``relearn_frames`` frames from there (its tracks coast).
4. The mask is warped back into the frame's coordinates (:meth:`Stabilizer.unwarp`).

**The first background** (``motion.bootstrap_s``, off by default). A model starts from the
first frame, so whoever stands in it is learnt as background: when they walk off, the place they
stood is a ghost for as long as the model takes to forget them (KNN's history is 500 frames).
Over the first ``bootstrap_s`` seconds the stage keeps :data:`BOOT_SAMPLES` frames, evenly
spaced; then the model starts again from their per-pixel median (what the scene showed most of
that time: the ground where people walked, and whoever stood still for more than half of it)
while the hold keeps the background it knew under this frame's foreground and the boxes it
holds (:meth:`MotionDetector.reseed`); the ghost filter's backgrounds take the median too. The
scene-background-initialisation methods of the SBI benchmark do the same with all the frames at
hand; here it costs the kept frames' memory at processing scale and nothing after.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..config import MotionConfig, StabilizeConfig
from .base import MotionDetector
from .stabilize import StabilizedFrame, Stabilizer

__all__ = ["MotionStage", "StageOutput", "sudden_change"]

#: the previous frame's motion is widened by this many pixels (a 2r+1 square) where the new
#: model takes the old background: objects move a little from one frame to the next
_REACH = 4
_WIDEN = cv2.getStructuringElement(cv2.MORPH_RECT, (2 * _REACH + 1, 2 * _REACH + 1))
#: frames of a new model in which the share of foreground is not taken as a sudden change:
#: some models call much of the frame foreground while they settle (CNT for its
#: min_pixel_stability frames, 15 by default)
_YOUNG = 25
#: frames kept for the first background's median (``motion.bootstrap_s``)
BOOT_SAMPLES = 11


@dataclass(frozen=True)
class StageOutput:
    """One frame of :meth:`MotionStage.apply`: the detector's ``raw`` mask in the frame's own
    coordinates (h, w uint8 0/255), the image the model saw (``view``: the frame in the
    reference frame's coordinates, or the frame itself), whether the model re-learnt at this
    frame after a sudden change (``relearned``), whether the reference moved on
    (``reanchored``), and the camera's motion since the previous frame while it moves (``step``:
    (2, 3), previous frame's pixels → this frame's, processing scale; see
    :attr:`StabilizedFrame.step`), and the pixels of ``raw`` that the detector holds for a
    stopped tracked object (``held``: :meth:`MotionDetector.held`, frame coordinates, or None)."""

    raw: np.ndarray
    view: np.ndarray
    relearned: bool = False
    reanchored: bool = False
    step: np.ndarray | None = None
    held: np.ndarray | None = None
    #: the first background (``motion.bootstrap_s``), in the frame's own coordinates, at the
    #: frame the model re-learnt from it: the other models of the scene take it too
    seed: np.ndarray | None = None


def sudden_change(fraction: float, jump: float, cfg: MotionConfig) -> bool:
    """Whether a frame with ``fraction`` of its pixels foreground and a mean brightness
    ``jump`` (grey levels, absolute) from the previous frame is a sudden change of the whole
    scene (``motion.relearn_fraction``, ``motion.relearn_brightness``; 0 switches either off)."""
    return ((cfg.relearn_fraction > 0 and fraction > cfg.relearn_fraction)
            or (cfg.relearn_brightness > 0 and jump > cfg.relearn_brightness))


def _to_view(mask: np.ndarray | bool | None, seen: StabilizedFrame) -> np.ndarray | bool | None:
    """A (h, w) bool mask of the frame in the reference frame's coordinates (others as given)."""
    if not isinstance(mask, np.ndarray):
        return mask
    h, w = mask.shape
    return cv2.warpAffine(mask.view(np.uint8), seen.transform, (w, h),
                          flags=cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP) > 0


def _mean(image: np.ndarray) -> float:
    """Mean grey level of ``image`` over all its channels."""
    m = cv2.mean(image)
    return float(np.mean(m[:image.shape[2]] if image.ndim == 3 else m[:1]))


class MotionStage:
    """The detector with compensation and sudden-change handling (see the module notes).

    Parameters
    ----------
    detector : the motion detector (:data:`~motiontrack.motion.DETECTORS`).
    motion : MotionConfig (its ``relearn_*`` keys).
    stabilize : StabilizeConfig (``enabled`` false: no compensation).
    """

    def __init__(self, detector: MotionDetector, motion: MotionConfig,
                 stabilize: StabilizeConfig, fps: float | None = None) -> None:
        self.detector = detector
        self.cfg = motion
        #: frames after which the model re-learns from the median of the first frames
        self._boot_at = int(round(motion.bootstrap_s * (fps or 25.0)))
        self._boot: list[np.ndarray] | None = [] if self._boot_at > 1 else None
        self._frames = 0
        self.stabilizer = Stabilizer(stabilize) if stabilize.enabled else None
        self._mean: float | None = None          # previous frame's mean brightness
        self._moving: np.ndarray | None = None   # previous frame's mask (model coordinates)
        self._calm = 0                           # frames before the next change is looked for
        self._young = _YOUNG                     # frames before the foreground share counts
        #: sudden changes the model re-learnt at, and reference frames taken after the first
        self.relearned = 0
        self.reanchored = 0

    def reset(self, detector: MotionDetector) -> None:
        """Start afresh with ``detector`` (a source discontinuity): new reference, no history."""
        self.detector = detector
        if self.stabilizer is not None:
            self.stabilizer.reset()
        self._mean = self._moving = None
        self._calm = 0
        self._young = _YOUNG
        self._boot = [] if self._boot_at > 1 else None
        self._frames = 0

    def relearn(self, image: np.ndarray | None = None) -> None:
        """The detector forgets its model and learns the scene afresh (from ``image``, a
        background in the coordinates of the frames the model sees, when given); see
        :meth:`MotionDetector.relearn`."""
        self.detector.relearn(image)
        self._moving = None
        self._young = _YOUNG

    def apply(self, image: np.ndarray, protect: np.ndarray | None = None,
              relearn: np.ndarray | bool | None = None) -> StageOutput:
        """The motion of ``image`` (the preprocessed frame); ``protect`` and ``relearn`` as
        :meth:`MotionDetector.apply`'s, masks in the frame's coordinates (``relearn`` goes only
        to a detector that ``relearns``)."""
        seen = self.stabilizer.apply(image) if self.stabilizer is not None else None
        view = image if seen is None else seen.image
        if seen is not None and seen.reanchored:
            self._follow(seen)
        if seen is not None and seen.transform is not None:
            protect, relearn = (_to_view(m, seen) for m in (protect, relearn))
        if self.detector.relearns:
            raw = self.detector.apply(view, protect, relearn)
        else:
            raw = self.detector.apply(view, protect)
        relearned = self._sudden(view, raw)
        seed = None if relearned else self._booted(view, raw, protect)
        if relearned or seed is not None:
            raw = self.detector.apply(view, None)
        held = self.detector.held()
        self._moving = raw
        if seen is not None:
            raw = self.stabilizer.unwarp(raw, seen)
            if held is not None:
                held = self.stabilizer.unwarp(held, seen)
        if seen is None:
            return StageOutput(raw, view, relearned, held=held, seed=seed)
        if seed is not None and seen.transform is not None:
            seed = self.stabilizer.unwarp(seed, seen)
        return StageOutput(raw, view, relearned, seen.reanchored, seen.step, held, seed)

    def _booted(self, view: np.ndarray, raw: np.ndarray,
                protect: np.ndarray | None) -> np.ndarray | None:
        """Keep ``view`` for the first background when it is due; at ``bootstrap_s`` re-learn
        the model from the median of the frames kept, the hold keeping its background under
        this frame's mask ``raw`` and the boxes it holds (``protect``), and return that median
        (see the module notes); None on every other frame."""
        if self._boot is None:
            return None
        self._frames += 1
        every = max(1, self._boot_at // (BOOT_SAMPLES - 1))
        if (self._frames - 1) % every == 0:
            self._boot.append(view.copy())
        if self._frames < self._boot_at:
            return None
        samples, self._boot = self._boot, None
        if len(samples) < 3 or any(v.shape != view.shape for v in samples):
            return None
        seed = np.median(np.stack(samples), axis=0).astype(np.uint8)
        keep = raw > 0
        if isinstance(protect, np.ndarray) and protect.shape == keep.shape:
            keep |= protect
        self.detector.reseed(seed, keep)
        self._young = _YOUNG
        return seed

    def _follow(self, seen: StabilizedFrame) -> None:
        """The reference moved on at ``seen``: the model re-learns from its background carried
        into the new reference."""
        old = self.detector.background()
        fill = seen.image
        if old is not None and old.ndim != fill.ndim:
            old = None
        self.relearn(self.stabilizer.to_anchor(old, seen, fill) if old is not None else fill)
        self.reanchored += 1
        self._boot = None   # the frames kept are in the old reference's coordinates

    def _sudden(self, view: np.ndarray, raw: np.ndarray) -> bool:
        """Look for a sudden change at this frame and re-learn when there is one."""
        mean, before = _mean(view), self._mean
        self._mean = mean
        if self._calm > 0:
            self._calm -= 1
            return False
        jump = abs(mean - before) if before is not None else 0.0
        self._young = max(0, self._young - 1)
        share = cv2.countNonZero(raw) / raw.size if not self._young else 0.0
        if not sudden_change(share, jump, self.cfg):
            return False
        self.relearn(self._seed(view, before, mean))
        self.relearned += 1
        self._calm = self.cfg.relearn_frames
        return True

    def _seed(self, view: np.ndarray, before: float | None, mean: float) -> np.ndarray:
        """The background the new model starts from after a sudden change: ``view``, except
        where the previous frame moved, which takes the old background scaled by the change of
        the mean brightness (``before`` → ``mean``)."""
        old, moving = self.detector.background(), self._moving
        if (old is None or moving is None or before is None or before <= 0
                or old.shape != view.shape or moving.shape != view.shape[:2]):
            return view
        near = cv2.dilate(moving, _WIDEN) > 0
        if not near.any():
            return view
        seed = view.copy()
        seed[near] = cv2.convertScaleAbs(old, alpha=mean / before)[near]
        return seed
