"""A class per track (``person``, ``vehicle``, ``other``) from evidence gathered over its life:
:class:`~.stage.TrackClassifier`, the stage after the tracker."""

from .stage import CLASS_IDS, CLASS_NAMES, TrackClassifier, class_id, class_name

__all__ = ["CLASS_IDS", "CLASS_NAMES", "TrackClassifier", "class_id", "class_name"]
