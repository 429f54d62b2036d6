"""Tracked runs shared by a whole test session.

A whole-pipeline run of a synthetic scene costs seconds; several tests assert on the same run
(its line counts, its zone counts, its event scores, its files). :class:`SceneRuns` runs each
``(scene, seed, options)`` once — ``synth-events`` for the ground truth, then ``track --scene``
on the rendered video — and hands every later caller the same :class:`SceneRun`. The
session-scoped ``scene_runs`` fixture (tests/conftest.py) holds the one instance.
"""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from motiontrack.cli import main
from motiontrack.io.events import read_events
from motiontrack.types import Event


@dataclass(frozen=True)
class SceneRun:
    """One tracked run of a synthetic scene with its scene file.

    ``gt_dir`` holds what ``synth-events`` wrote (``scene.toml``, ``events.jsonl``), ``run_dir``
    what ``track --scene`` wrote (``events.jsonl``, ``summary.json``, ...).
    """

    gt_dir: Path
    run_dir: Path
    gt: tuple[Event, ...]      # synth-events: the scene's exact events
    pred: tuple[Event, ...]    # track --scene on the rendered video
    summary: dict              # the run's summary.json

    def crossings(self, which: str) -> Counter:
        """``(line, direction)`` -> crossings, of ``"gt"`` or ``"pred"``."""
        return Counter((e.line, e.direction) for e in self._events(which)
                       if e.type == "line_cross")

    def count(self, which: str, kind: str) -> int:
        """How many events of type ``kind`` in ``"gt"`` or ``"pred"``."""
        return sum(e.type == kind for e in self._events(which))

    def _events(self, which: str) -> tuple[Event, ...]:
        return self.gt if which == "gt" else self.pred


class SceneRuns:
    """``runs(name, seed, *options)`` → the :class:`SceneRun` of ``track synth:NAME?seed=SEED
    --scene … --no-video OPTIONS``, run on the first call and cached under ``root``."""

    def __init__(self, root: Path):
        self.root = Path(root)
        self._runs: dict[tuple, SceneRun] = {}

    def __call__(self, name: str, seed: int, *options: str) -> SceneRun:
        key = (name, seed, options)
        if key not in self._runs:
            self._runs[key] = self._track(name, seed, options, len(self._runs))
        return self._runs[key]

    def _track(self, name: str, seed: int, options: tuple[str, ...], n: int) -> SceneRun:
        spec = f"synth:{name}?seed={seed}"
        d = self.root / f"{n:03d}-{name}-{seed}"
        assert main(["synth-events", spec, "-o", str(d / "gt")]) == 0
        assert main(["track", spec, "--scene", str(d / "gt" / "scene.toml"), "--no-video",
                     *options, "-o", str(d / "run")]) == 0
        return SceneRun(d / "gt", d / "run",
                        tuple(read_events(d / "gt" / "events.jsonl").events),
                        tuple(read_events(d / "run" / "events.jsonl").events),
                        json.loads((d / "run" / "summary.json").read_text()))
