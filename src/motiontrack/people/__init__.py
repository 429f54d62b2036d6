"""People-specific modules of the Reading People Tracker: heads, active shapes, HOG.

* :mod:`.heads` — human feature (head) detector and head-based splitting of merged regions;
* :mod:`.bspline`, :mod:`.shape_model` — closed B-spline outlines and the point-distribution model;
* :mod:`.shape_tracker` — active shape tracker fitted to the difference image (its numerics for
  several people at once in :mod:`.shape_batch`);
* :mod:`.hog` — OpenCV's HOG people detector (whole frame or motion regions);
* :mod:`.training` — training a shape model from ground truth or synthetic scenes;
* :mod:`.stage` — :class:`PeopleStage`, which wires them for the pipeline, one call per frame::

    stage = PeopleStage(cfg.people)
    regions, found = stage.process(frame.image, background, mask, regions, tracks, work=small)
    tracks = tracker.update(regions, hypotheses=..., located=...)

``tracks`` are the region tracker's tracks from the previous frame (the stage runs before the
tracker update). ``regions`` come back with merged regions split at heads and HOG detections when
HOG is on. For people whose shape is still tracked but no region covers them any more (the motion
detector lost them), ``found.hypotheses_by_track`` (a :class:`~motiontrack.types.PeopleFrame`)
holds the fitted shape's box per track id;
with ``hypotheses`` on, the pipeline offers it to that one lost track as a measurement that can
never start a new track (Siebel's thesis, section 4.5: the region tracker takes the shape's box as
its hypothesis). See ``docs/people.md``.
"""

from ..config import PeopleConfig
from .stage import PeopleStage, head_params

__all__ = ["PeopleConfig", "PeopleStage", "head_params"]
