"""Motion detection: image → foreground mask (uint8, 0 or 255), plus mask clean-up.

Detectors are plug-ins in :data:`DETECTORS`; create one with ``DETECTORS.create(name, **params)``.
Each detector has ``apply(image) -> mask`` and, where it keeps a background model,
``background() -> image``.
"""

from .base import DETECTORS, MotionDetector
from .cleanup import clean_mask
from . import detectors as _detectors  # noqa: F401  (registers the built-in detectors)
from . import samples as _samples  # noqa: F401  (registers the sample-based model)
from . import bgslibrary as _bgslibrary  # noqa: F401  (registers BGSLibrary's models)

__all__ = ["DETECTORS", "MotionDetector", "clean_mask", "create_detector"]


def create_detector(cfg, fps: float | None = None) -> MotionDetector:
    """The detector selected by a :class:`~motiontrack.config.MotionConfig`, for a source of
    ``fps`` frames a second (None: unknown, taken as 25)."""
    detector = DETECTORS.create(cfg.method, **cfg.params_for())
    detector.set_rate(fps or 25.0)
    return detector
