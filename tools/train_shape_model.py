#!/usr/bin/env python
"""Reproduce the shipped default shape model ``src/motiontrack/data/shape_model_default.npz``.

It is trained only on the synthetic figures rendered by :mod:`motiontrack.synth` (exact masks of
isolated, fully visible people), so it can be redistributed with the package::

    .venv/bin/python tools/train_shape_model.py            # writes the default model
    .venv/bin/python tools/train_shape_model.py -o my.npz  # somewhere else

The same recipe is ``motiontrack shape train synth:walker ...``; see docs/people.md.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from motiontrack.people.shape_model import default_model_path
from motiontrack.people.training import DEFAULT_TRAINING, save_model, train_from_synth


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", type=Path, default=default_model_path())
    ap.add_argument("--control-points", type=int, default=32)
    ap.add_argument("--xi", type=float, default=0.95)
    ap.add_argument("--every", type=int, default=3)
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    model = train_from_synth(DEFAULT_TRAINING, n_control=args.control_points, xi=args.xi,
                             every=args.every)
    save_model(model, args.out)
    print(f"{args.out}: {model.n_control} control points, {model.n_modes} modes "
          f"({model.meta['explained']:.3f} of the variance), {model.meta['samples']} outlines, "
          f"{args.out.stat().st_size} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
