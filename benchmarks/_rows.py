"""The ``--row NAME=KEY=VALUE,KEY=VALUE`` option of the benchmarks that compare settings side by
side: a row's name and its ``--set`` overrides."""

from __future__ import annotations

import argparse


def parse_row(text: str) -> tuple[str, list[str]]:
    """``NAME=KEY=VALUE[,KEY=VALUE...]`` → ``(NAME, ["KEY=VALUE", ...])``."""
    name, _, sets = text.partition("=")
    if not sets:
        raise argparse.ArgumentTypeError(f"--row needs NAME=KEY=VALUE[,KEY=VALUE], got {text!r}")
    return name, [s for s in sets.split(",") if s]
