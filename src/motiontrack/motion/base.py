"""The motion-detector interface and registry."""

from __future__ import annotations

import numpy as np

from ..registry import Registry


class MotionDetector:
    """Turns each frame into a foreground mask.

    ``apply`` takes the preprocessed frame (``(h, w)`` or ``(h, w, 3)`` uint8) and returns a
    ``(h, w)`` uint8 mask with 255 = moving and 0 = background. Shadow pixels are never foreground.
    """

    #: whether the detector wants colour input (e.g. GSOC); the pipeline then skips grayscale
    wants_color = False
    #: whether ``apply`` wants a ``protect`` mask (selective background update switched on)
    protect = False
    #: whether ``apply`` takes a ``relearn`` request (re-learn the whole frame or some pixels)
    relearns = False
    #: the ``protect`` mask holds only the tracks slower than this (box heights a second; None:
    #: every track that has moved)
    protect_speed: float | None = None
    #: whether the model takes another shadow test in a scene of vehicles (:meth:`vehicle_scene`)
    switches_shadows = False
    #: whether the model finds ghosts itself (it absorbs them by feedback, as SuBSENSE does): the
    #: pipeline's ghost filter is not run on its mask
    own_ghosts = False

    def apply(self, image: np.ndarray, protect: np.ndarray | None = None) -> np.ndarray:  # pragma: no cover
        """Foreground mask of ``image``.

        ``protect`` (optional, (h, w) bool) marks pixels covered by tracked objects: detectors
        that support it do not learn them into the background there, so a
        person who stops walking does not fade away (selective update, as in the Reading People
        Tracker's background maintenance). The pipeline passes it when ``self.protect`` is true.
        Detectors with ``relearns`` also take ``relearn``: ``True`` to learn the frame afresh (a
        global change of the picture), or a (h, w) bool mask of pixels to re-learn at once (the
        place an object left).
        """
        raise NotImplementedError

    def set_rate(self, fps: float) -> None:
        """The source's frame rate, for detectors with durations in seconds (default: none)."""

    def vehicle_scene(self, vehicles: bool) -> None:
        """Whether the scene's tracks are mostly vehicles, for a model whose shadow test
        depends on it (``switches_shadows``; default: none)."""

    def relearn(self, image: np.ndarray | None = None) -> None:  # pragma: no cover
        """Forget the background model and learn the scene afresh: after a sudden change of the
        whole picture (a light switched on, the camera's reference frame moved).

        ``image`` (optional, like :meth:`apply`'s input) is a background the caller already
        knows, in the coordinates of the frames that follow: the new model starts from it, so
        the next frame's objects stand out at once. Without it the model starts from the next
        frame (which then shows no motion)."""
        raise NotImplementedError

    def reseed(self, image: np.ndarray, keep: np.ndarray | None = None) -> None:
        """Start the background model again from ``image``, a background known for the frames
        to come (the first background of ``motion.bootstrap_s``); ``keep`` ((h, w) bool): the
        pixels the last frame showed as foreground, where what the detector holds for stopped
        tracked objects keeps the background it knew (default: :meth:`relearn`)."""
        self.relearn(image)

    def background(self) -> np.ndarray | None:
        """Current background estimate (for `--save background`), or None."""
        return None

    def held(self) -> np.ndarray | None:
        """The pixels of the last mask that are foreground only because a stopped tracked object
        is kept there (uint8 0/255, the frame's shape), or None when there are none: the ghost
        filter leaves them alone (default: none)."""
        return None


DETECTORS: Registry[MotionDetector] = Registry("motion detector")
