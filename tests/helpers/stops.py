"""A person who walks in, stands still, and walks on: the synthetic scene of the tests of
stopped objects, and the frames each track of a pipeline run over it was reported in."""

from __future__ import annotations

from motiontrack.pipeline import Pipeline
from motiontrack.synth.render import Person
from motiontrack.synth.sequence import SyntheticScene
from motiontrack.types import Frame


def stopping_person(size: tuple[int, int], fps: float, walk_to: int, stand: int, after: int,
                    x0: float, y0: float, speed: float, height: float,
                    t0: float) -> SyntheticScene:
    """One person walking right at ``speed`` px a frame from ``x0`` who stops at frame
    ``walk_to`` for ``stand`` frames and walks on; ``after`` frames follow the stop."""
    p = Person(id=1, x0=x0, y0=y0, vx=speed, vy=0.0, height=height, t0=t0,
               turns=((float(walk_to), 0.0, 0.0), (float(walk_to + stand), speed, 0.0)))
    return SyntheticScene("stop", 0, size[0], size[1], fps, walk_to + stand + after,
                          people=(p,))


def frames_by_track(cfg, scene: SyntheticScene) -> dict[int, list[int]]:
    """Track id → the frames it was reported in, ``scene`` run through a :class:`Pipeline`
    with ``cfg``."""
    pipe = Pipeline(cfg, (scene.width, scene.height), fps=scene.fps)
    seen: dict[int, list[int]] = {}
    for i in range(scene.n_frames):
        r = pipe.process(Frame(index=i, image=scene.frame(i), timestamp=i / scene.fps))
        for t in r.tracks:
            seen.setdefault(t.id, []).append(i)
    return seen
