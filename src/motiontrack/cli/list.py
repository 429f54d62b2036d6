"""``motiontrack list``: every plug-in by stage, the video codecs this installation can encode,
and the synthetic scenes."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("list", help="list presets, motion detectors, trackers, the video codecs "
                                    "this installation encodes and synthetic scenes")
    p.set_defaults(func=cmd_list)


def cmd_list(args) -> int:
    from ..motion import DETECTORS
    from ..tracking.single import SINGLE_TRACKERS
    from ..tracking import detections as _detections  # noqa: F401  (registers its tracker)
    from ..tracking.tracker import TRACKERS

    from ..config import presets
    from ..io.video import encodable_codecs
    from ..motion.bgslibrary import algorithms

    groups = [("presets (motiontrack track --preset NAME)", presets()),
              ("motion detectors (--set motion.method=NAME)", DETECTORS.describe()),
              ("BGSLibrary models (--set motion.method=bgslibrary "
               "--set motion.bgslibrary.algorithm=NAME)",
               {n: "" for n in algorithms()} or {"(none)": "pybgs is not installed"}),
              ("trackers (--set tracker.method=NAME)", TRACKERS.describe()),
              ("single-object trackers (motiontrack follow --tracker NAME)",
               SINGLE_TRACKERS.describe()),
              ("video codecs this installation encodes (--codec NAME)", encodable_codecs())]
    try:
        from ..synth import scene_summaries

        groups.append(("synthetic scenes (SOURCE = synth:NAME)", dict(scene_summaries())))
    except ImportError:  # pragma: no cover
        pass
    for title, items in groups:
        print(title)
        for name, doc in items.items():
            print(f"  {name:<12} {doc}".rstrip())
    return 0
