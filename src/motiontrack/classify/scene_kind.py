"""Whether a scene shows mostly vehicles, from the classes of its recent tracks.

The motion model's shadow test takes a darker copy of the ground for a shadow; a grey or silver
car on asphalt is such a copy over much of its body, so the default test cuts cars into pieces
while it keeps people's shadows off them. The pipeline asks :class:`VehicleScene` each frame and
gives the model its vehicles' shadow threshold while the answer is yes
(``motion.knn.vehicle_shadow_threshold``, docs/pipeline.md "Shadows"), and closes the
silhouettes of the mask it reports (a car has no gaps a pixel or two wide; a person's legs do:
docs/pipeline.md "Regions").
"""

from __future__ import annotations

import collections
from typing import Iterable

__all__ = ["VehicleScene"]


class VehicleScene:
    """The labels of the last :attr:`RECENT` tracks that had a person or vehicle label, each
    weighed by the frames it was seen in: the scene is a vehicles' scene when at least
    :attr:`MIN_VEHICLES` of them are vehicles and the vehicles' frames are at least
    :attr:`MAJORITY` times the people's (a flickering light, or a person near the camera whose
    box the frame's edge cuts square, does not make an office a road)."""

    RECENT = 100
    MIN_VEHICLES = 2
    MAJORITY = 2.0

    def __init__(self) -> None:
        #: track id → [its latest label, frames it was seen in]
        self._labels: collections.OrderedDict[int, list] = collections.OrderedDict()

    def reset(self) -> None:
        self._labels.clear()

    def update(self, tracks: Iterable) -> bool:
        """Take the labels of ``tracks`` (a frame's tracks, with ``id`` and ``label``); whether
        the scene is a vehicles' scene now."""
        for t in tracks:
            if t.label in ("person", "vehicle"):
                seen = self._labels.get(t.id)
                self._labels[t.id] = [t.label, 1 if seen is None else seen[1] + 1]
                self._labels.move_to_end(t.id)
                if len(self._labels) > self.RECENT:
                    self._labels.popitem(last=False)
        vehicles = [n for label, n in self._labels.values() if label == "vehicle"]
        people = sum(n for label, n in self._labels.values() if label == "person")
        return len(vehicles) >= self.MIN_VEHICLES and sum(vehicles) >= self.MAJORITY * max(people, 1)
