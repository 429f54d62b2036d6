"""``synth:NAME?key=value`` as a video source: the scene rendered frame by frame, with its exact
ground truth. Importing :mod:`motiontrack.synth` registers the ``synth`` scheme with
:data:`motiontrack.io.sources.SCHEMES`.
"""

from __future__ import annotations

from typing import Iterator

from ..io.sources import SCHEMES, Source, SourceInfo
from ..types import Annotations, Frame

__all__ = ["SyntheticSource"]


@SCHEMES.register("synth", "a synthetic scene with exact ground truth: synth:NAME?key=value")
class SyntheticSource(Source):
    """A synthetic scene (``synth:NAME?seed=..``) rendered on the fly, with exact ground truth."""

    def __init__(self, spec: str, start: int = 0, max_frames: int = 0) -> None:
        # the scenes and their drawing load with the first synth: source, not with the scheme
        from .scenes import parse_synth_spec

        super().__init__(start, max_frames)
        self.scene = parse_synth_spec(spec)
        s = self.scene
        self.info = SourceInfo(name=spec, width=s.width, height=s.height, fps=float(s.fps),
                               frame_count=s.n_frames)

    def ground_truth(self) -> Annotations:
        return self.scene.ground_truth()

    def __iter__(self) -> Iterator[Frame]:
        end = self.scene.n_frames if not self.max_frames else min(self.scene.n_frames,
                                                                  self.start + self.max_frames)
        for i in range(self.start, end):
            yield Frame(index=i, image=self.scene.frame(i), timestamp=i / self.info.fps,
                        discontinuity=self.seek_mark(i))
