"""``motiontrack synth-events``: a synthetic scene's scene file, ground truth and exact
ground-truth events, to score ``track --scene`` and ``analyze`` with ``evaluate-events``."""

from __future__ import annotations

import argparse
from pathlib import Path


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "synth-events",
        help="write a synthetic scene's scene file, ground truth and ground-truth events",
        description="For a synthetic scene (synth:NAME?key=value, as for track) write, in the "
                    "output folder, scene.toml (its lines and zones, for --scene), gt.txt (its "
                    "ground-truth tracks, MOTChallenge) and events.jsonl (the events its rules "
                    "give on the ground truth: exact, for evaluate-events --gt). See "
                    "docs/synthetic.md.")
    p.add_argument("spec", help="synthetic scene, e.g. synth:leftbag?seed=3 (or just leftbag)")
    p.add_argument("-o", "--out", type=Path, required=True, help="output folder")
    p.add_argument("--force", action="store_true", help="replace existing outputs")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..errors import check_output_path
    from ..io.atomic import atomic_write_text, writing_outputs
    from ..io.events import write_events
    from ..io.mot import write_mot
    from ..synth import parse_synth_spec

    spec = args.spec if args.spec.startswith("synth:") else f"synth:{args.spec}"
    scene = parse_synth_spec(spec)
    check_output_path(args.out, "-o", folder=True)
    paths = {k: args.out / k for k in ("scene.toml", "gt.txt", "events.jsonl")}
    # the folder's lock, as a run takes it: never a gt.txt into a folder a run is writing
    with writing_outputs(paths.values(), args.force):
        events = scene.ground_truth_events()
        atomic_write_text(paths["scene.toml"], scene.scene_toml())
        write_mot(scene.ground_truth(), paths["gt.txt"], kind="gt")
        write_events(paths["events.jsonl"], events, scene.fps, source=scene.spec,
                     scene=str(paths["scene.toml"]))
    kinds: dict[str, int] = {}
    for e in events:
        kinds[e.type] = kinds.get(e.type, 0) + 1
    print(f"wrote {args.out}: scene.toml, gt.txt, events.jsonl ({len(events)} events"
          + "".join(f", {n} {k}" for k, n in kinds.items()) + f") for {scene.spec}")
    return 0
