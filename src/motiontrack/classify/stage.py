"""The class of each track, from evidence accumulated over its life (docs/classes.md).

Each frame a track is measured in (``time_since_update == 0``) casts one vote:

* **with a camera calibration** (``measure.camera``): the box's height on the ground plane
  (:func:`~motiontrack.calibrate.measure.box_heights`), its width in metres at that depth
  (``w * height_m / h``) and its ground speed over the last second
  (:class:`~motiontrack.speed.WindowSpeed` on the foot point). A ``person`` is
  ``person_min_height_m``-``person_max_height_m`` tall, at most ``person_max_width_m`` wide
  and no faster than ``person_max_speed_mps``; a ``vehicle`` is at least
  ``vehicle_min_width_m`` wide or faster than a person. A box whose foot point is above the
  horizon (or a camera without rays) votes by the image evidence below.
* **without one**: the box's aspect (height / width) and its speed in box heights per second
  (scale free: a walker covers about one of its own heights a second, a car on a road
  several). A ``person`` is at least ``person_aspect`` tall for its width and no faster than
  ``person_max_speed``; a ``vehicle`` is at most ``vehicle_aspect`` tall for its width or
  faster than a person.

A frame that fits neither votes ``other``. OpenCV's HOG people detector (``hog``: ``daimler``
or ``default``; :meth:`~motiontrack.people.hog.HOGPeopleDetector.people_in_box`) looks at the
boxes of a few measured tracks a frame in the pipeline's processing-scale frame: each person it
finds whose centre lies in the box casts ``hog_vote`` votes for ``person``; a miss casts none
(HOG misses many people). It looks at tracks no faster than a person whose class is not yet
``person`` or whose box does not look like one this frame (people merged side by side into a
wide blob), each at most every ``hog_every`` measured frames and at most ``hog_per_frame``
tracks a frame, vehicle-like tracks first. With the user's detector (``detector.model``), a
detection matched to a measured track (IoU at least ``detector.match_iou``) casts
``detector.vote`` more votes for its class (:func:`class_of`: ``person``; ``bicycle``, ``car``,
``motorcycle``, ``bus``, ``truck``... a ``vehicle``; any other name ``other``).

A track's class is the class with the most votes
once it has ``min_frames`` of them (``other`` before), its confidence that class's share of
the votes. Per-frame votes, not per-frame classes: a person merged for a few frames with
a neighbour into a wide blob keeps the class of the rest of its life.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Sequence

import numpy as np

from ..config import ClassesConfig
from ..speed import WindowSpeed
from ..types import Track

__all__ = ["CLASS_NAMES", "CLASS_IDS", "TrackClassifier", "class_id", "class_name", "class_of"]

#: the classes a track can have
CLASS_NAMES = ("person", "vehicle", "other")
#: each class's number in the class column of ``tracks.txt`` (MOT17's numbering: 1
#: pedestrian, 3 car; 0 other); -1 is a row without a class
CLASS_IDS = {"person": 1, "vehicle": 3, "other": 0}
#: our class of each MOT16/17/20 ground-truth class: pedestrian, person on vehicle and static
#: person are people; car, bicycle, motorbike and non-motorized vehicle vehicles; distractors,
#: occluders and reflections (8-12) other
_NAMES_BY_ID = {0: "other", 1: "person", 2: "person", 3: "vehicle", 4: "vehicle", 5: "vehicle",
                6: "vehicle", 7: "person", 8: "other", 9: "other", 10: "other", 11: "other",
                12: "other"}
_PERSON, _VEHICLE, _OTHER = range(3)


#: detector class names (COCO's and common others) that are a ``vehicle``
VEHICLE_NAMES = frozenset({"bicycle", "car", "motorcycle", "motorbike", "bus", "truck", "van",
                           "train", "vehicle", "tram", "scooter"})


def class_of(detector_name: str) -> str:
    """Our class of a detector's class name (``person``, ``car``...)."""
    name = detector_name.strip().lower()
    if name in ("person", "pedestrian", "people"):
        return "person"
    return "vehicle" if name in VEHICLE_NAMES else "other"


def class_id(name: str) -> int:
    """The class column's number of class ``name`` (-1 for none, ``""``)."""
    return CLASS_IDS.get(name, -1)


def class_name(number: int) -> str:
    """The class of a class column's number: ours (:data:`CLASS_IDS`) or a MOTChallenge
    ground truth's (1-12); ``""`` for -1 or an unknown number."""
    return _NAMES_BY_ID.get(int(number), "")


#: the shortest box (processing pixels) HOG looks at: shorter people would be magnified more
#: than 4 times to fill the window, which leaves no gradients to see
_HOG_MIN_HEIGHT = 16.0


class _Evidence:
    """One track's votes, its speed window, whether its last speed was a person's (known and
    no faster than one), when HOG last looked at it (measured frames ago) and this frame's
    vote."""

    __slots__ = ("votes", "speed", "last_seen", "slow", "speed_known", "since_hog", "vote")

    def __init__(self, fps: float) -> None:
        self.votes = np.zeros(3, dtype=np.int64)
        self.speed = WindowSpeed(fps=fps)
        self.last_seen = 0
        self.slow = False
        self.speed_known = False
        self.since_hog = 1 << 30
        self.vote = _OTHER


class TrackClassifier:
    """Classes of tracks, frame by frame (:meth:`update`).

    Parameters
    ----------
    cfg : ClassesConfig
    fps : frames per second of the source (None = 25): speeds are per second.
    camera : a camera model fitted to the source (metres), or None (image evidence only).
    """

    def __init__(self, cfg: ClassesConfig, fps: float | None = None, camera: Any = None) -> None:
        self.cfg = cfg
        self.fps = float(fps) if fps and math.isfinite(fps) and fps > 0 else 25.0
        self.camera = camera if camera is not None and hasattr(camera, "rays") else None
        self.hog = None
        if cfg.hog != "off":
            from ..people.hog import HOGParams, HOGPeopleDetector

            self.hog = HOGPeopleDetector(HOGParams(model=cfg.hog, hit_threshold=cfg.hog_threshold))
        #: boxes HOG looked at and people it found in them so far (benchmarks/classes.py)
        self.hog_looks = self.hog_found = 0
        self._tracks: dict[int, _Evidence] = {}
        self._frames = 0
        #: frames after which the evidence of a track not seen since is dropped
        self._keep = int(60 * self.fps)

    def reset(self) -> None:
        """Forget every track (a discontinuity ended them)."""
        self._tracks.clear()

    def confirm(self, earlier: Sequence[tuple[int, Track]], frame: int) -> None:
        """The votes of the tentative frames of the tracks confirmed at ``frame`` (0-based, the
        frame :meth:`update` is called for next): ``(frame, Track)`` pairs, each measured in its
        frame (:attr:`~motiontrack.tracking.tracker.MultiObjectTracker.confirmed_earlier`). A
        track then has its class from the frame it is confirmed in, as if it had been classified
        from its first frame (HOG aside, which saw none of them)."""
        by_frame: dict[int, list[Track]] = {}
        for f, t in earlier:
            by_frame.setdefault(f, []).append(t)
        for f in sorted(by_frame):
            # the classifier's own count of that frame (it counts its updates)
            self._vote(by_frame[f], self._frames + 1 - (frame - f))

    def label(self, tid: int) -> tuple[str, float]:
        """The class and confidence of track ``tid`` now (``("other", 0.0)`` when unknown)."""
        ev = self._tracks.get(tid)
        return ("other", 0.0) if ev is None else self._decide(ev.votes)

    def update(self, tracks: Sequence[Track], detections: Any = None,
               match_iou: float = 0.3, weight: int = 5, image: np.ndarray | None = None,
               scale: float = 1.0) -> list[Track]:
        """The tracks of one frame with :attr:`Track.label` and :attr:`Track.label_score` set,
        after the votes of the measured ones were counted: their own, ``weight`` for the
        class of the detection (``boxes``, :meth:`name`; the user's detector) each matches, and
        HOG's (``hog``) in ``image``, the frame at ``scale`` of the original (boxes are in
        original pixels; None = no HOG this frame)."""
        self._frames += 1
        measured = [t for t in tracks if t.time_since_update == 0]
        if measured:
            self._vote(measured)
            if detections is not None and len(detections):
                self._detector_votes(measured, detections, match_iou, weight)
            if self.hog is not None and image is not None:
                self._hog_votes(measured, image, scale)
        if len(self._tracks) > 64 and self._frames % 256 == 0:
            self._forget()
        out = []
        for t in tracks:
            name, conf = self.label(t.id)
            out.append(replace(t, label=name, label_score=conf))
        return out

    # -------------------------------------------------------------------------------- votes
    def _vote(self, tracks: Sequence[Track], at: int | None = None) -> None:
        """One vote of each of ``tracks``, measured at the classifier's frame count ``at``
        (None: this frame)."""
        boxes = np.array([t.box.as_array() for t in tracks], dtype=np.float64)
        evs = []
        for t in tracks:
            ev = self._tracks.get(t.id)
            if ev is None:
                ev = self._tracks[t.id] = _Evidence(self.fps)
            ev.last_seen = self._frames if at is None else at
            evs.append(ev)
        votes = self._image_votes(boxes, evs)
        if self.camera is not None:
            metric = self._metric_votes(boxes, evs)
            votes = np.where(metric >= 0, metric, votes)
        for ev, v in zip(evs, votes.tolist()):
            ev.votes[v] += 1
            ev.vote = v
            ev.since_hog += 1

    def _detector_votes(self, tracks: Sequence[Track], detections: Any, match_iou: float,
                        weight: int) -> None:
        from ..detect.fuse import matches   # with the user's detector only

        boxes = np.array([t.box.as_array() for t in tracks], dtype=np.float64)
        for i, j in matches(boxes, detections.boxes, match_iou):
            k = CLASS_NAMES.index(class_of(detections.name(j)))
            self._tracks[tracks[i].id].votes[k] += weight

    def _hog_votes(self, tracks: Sequence[Track], image: np.ndarray, scale: float) -> None:
        """``hog_vote`` votes for ``person`` per HOG person centred in the box of each track
        :meth:`_hog_candidates` picks."""
        c = self.cfg
        for t in self._hog_candidates(tracks, scale):
            ev = self._tracks[t.id]
            ev.since_hog = 0
            self.hog_looks += 1
            x, y, w, h = t.box.as_array().tolist()
            found = sum(1 for r in self.hog.people_in_box(image, (x, y, w, h), scale)
                        if x <= r.box.center[0] <= x + w and y <= r.box.center[1] <= y + h)
            ev.votes[_PERSON] += c.hog_vote * found
            self.hog_found += found

    def _hog_candidates(self, tracks: Sequence[Track], scale: float) -> list[Track]:
        """The measured tracks HOG looks at this frame, at most ``hog_per_frame``: no faster
        than a person, not looked at in their last ``hog_every`` measured frames, tall enough,
        and either not yet a ``person`` or not looking like one this frame; vehicles first,
        then undecided tracks (``other``), then people in a wide box, each the longest unseen
        first."""
        c = self.cfg
        ranked = []
        for t in tracks:
            ev = self._tracks[t.id]
            if not ev.slow or ev.since_hog < c.hog_every or t.box.h * scale < _HOG_MIN_HEIGHT:
                continue
            k = CLASS_NAMES.index(self._decide(ev.votes)[0])
            if k == _PERSON and ev.vote == _PERSON:
                continue
            rank = {_VEHICLE: 0, _OTHER: 1, _PERSON: 2}[k]
            ranked.append((rank, -ev.since_hog, t.id, t))
        ranked.sort(key=lambda r: r[:3])
        return [r[3] for r in ranked[:c.hog_per_frame]]

    def _image_votes(self, boxes: np.ndarray, evs: list[_Evidence]) -> np.ndarray:
        """(N,) votes from the boxes' aspect and their speed in heights per second."""
        c = self.cfg
        w, h = boxes[:, 2], boxes[:, 3]
        cx, cy = boxes[:, 0] + w / 2.0, boxes[:, 1] + h / 2.0
        if self.camera is None:
            pace = np.array([_speed(ev, x, y) for ev, x, y in zip(evs, cx, cy)]) / h
            known = np.array([ev.speed_known for ev in evs], dtype=bool)
            for ev, slow in zip(evs, (known & (pace <= c.person_max_speed)).tolist()):
                ev.slow = slow
        else:   # the windows hold ground positions: the image test goes without speed
            pace = np.zeros(len(boxes))
        aspect = h / w
        person = (aspect >= c.person_aspect) & (pace <= c.person_max_speed)
        vehicle = (aspect <= c.vehicle_aspect) | (pace > c.person_max_speed)
        return np.where(person, _PERSON, np.where(vehicle, _VEHICLE, _OTHER))

    def _metric_votes(self, boxes: np.ndarray, evs: list[_Evidence]) -> np.ndarray:
        """(N,) votes from height, width and ground speed in metres; -1 where the box cannot
        be measured (foot point above the horizon)."""
        from ..calibrate.measure import box_heights, world_positions

        c = self.cfg
        height = box_heights(boxes, self.camera)
        width = boxes[:, 2] * height / boxes[:, 3]
        foot = world_positions(boxes, self.camera)
        speed = np.array([_speed(ev, X, Y) if math.isfinite(X) and math.isfinite(Y) else 0.0
                          for ev, (X, Y) in zip(evs, foot.tolist())])
        ok = np.isfinite(height) & (height > 0)
        for ev, (X, Y), v in zip(evs, foot.tolist(), speed.tolist()):
            ev.slow = (math.isfinite(X) and math.isfinite(Y) and ev.speed_known
                       and v <= c.person_max_speed_mps)
        person = ((height >= c.person_min_height_m) & (height <= c.person_max_height_m)
                  & (width <= c.person_max_width_m) & (speed <= c.person_max_speed_mps))
        vehicle = (width >= c.vehicle_min_width_m) | (speed > c.person_max_speed_mps)
        votes = np.where(person, _PERSON, np.where(vehicle, _VEHICLE, _OTHER))
        return np.where(ok, votes, -1)

    def _decide(self, votes: np.ndarray) -> tuple[str, float]:
        total = int(votes.sum())
        if total < self.cfg.min_frames:
            return "other", 0.0
        k = int(np.argmax(votes))
        return CLASS_NAMES[k], round(float(votes[k]) / total, 3)

    def _forget(self) -> None:
        old = self._frames - self._keep
        for tid in [t for t, ev in self._tracks.items() if ev.last_seen < old]:
            del self._tracks[tid]


def _speed(ev: _Evidence, x: float, y: float) -> float:
    """The track's speed per second over the last second after adding ``(x, y)`` (0 while
    the window is too short)."""
    v = ev.speed.add(ev.last_seen, float(x), float(y))
    ev.speed_known = v is not None
    return 0.0 if v is None else float(v)
