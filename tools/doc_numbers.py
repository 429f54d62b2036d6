"""Re-run the command transcripts of the docs and compare the numbers they show.

A transcript is a fenced code block of README.md or docs/*.md preceded by a marker line::

    <!-- checked -->            run by the fast suite (tests/test_doc_numbers.py)
    <!-- checked: slow -->      run by the slow suite only

whose first line is the command (``motiontrack ...``, optionally after ``$ ``; a line ending in
``\\`` continues on the next) and whose other lines are what it prints, or a selection of those
lines. ``../shared/data`` in the command is the data folder (``MOTIONTRACK_DATA``); the command
runs in a scratch folder, so its outputs land there.

Each shown line must match a printed line with the same text around its numbers, and each
number must equal the printed one to the digits shown (``0.566`` matches 0.5655 to 0.5665).
A shown line ending in ``...`` matches a printed line that starts like it.

    .venv/bin/python tools/doc_numbers.py            # every transcript; exit 1 on a drift
    .venv/bin/python tools/doc_numbers.py --fast     # only those not marked slow
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import os
import re
import shlex
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MARKER = re.compile(r"^<!--\s*checked(?::\s*(?P<tags>[\w ,]+))?\s*-->\s*$")
NUMBER = re.compile(r"[-+−]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


@dataclass(frozen=True)
class Transcript:
    """One checked block: where it is, the command, the lines it shows."""

    path: Path
    line: int           # 1-based line of the command
    command: str
    expected: tuple[str, ...]
    slow: bool

    @property
    def where(self) -> str:
        return f"{self.path.relative_to(ROOT)}:{self.line}"


def transcripts(paths: list[Path] | None = None) -> list[Transcript]:
    """Every checked transcript of ``paths`` (default README.md and docs/*.md)."""
    paths = paths if paths is not None else [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    found = []
    for path in paths:
        lines = path.read_text(encoding="utf-8").splitlines()
        for i, text in enumerate(lines[:-2]):
            m = MARKER.match(text.strip())
            if not m or not lines[i + 1].startswith("```"):
                continue
            end = next(j for j in range(i + 2, len(lines)) if lines[j].startswith("```"))
            block = lines[i + 2:end]
            cmd, k = [], 0
            while k < len(block):
                part = block[k].strip()
                k += 1
                cmd.append(part.rstrip("\\").strip())
                if not part.endswith("\\"):
                    break
            command = " ".join(cmd).removeprefix("$ ").strip()
            tags = {t.strip() for t in (m.group("tags") or "").split(",")}
            found.append(Transcript(path, i + 3, command, tuple(ln for ln in block[k:] if ln.strip()),
                                    "slow" in tags))
    return found


def data_dir() -> Path:
    return Path(os.environ.get("MOTIONTRACK_DATA", ROOT.parent / "shared" / "data")).resolve()


def run(command: str, cwd: Path) -> str:
    """What ``command`` (a motiontrack command line) prints to standard output, run in ``cwd``."""
    from motiontrack.cli import main

    argv = shlex.split(command.replace("../shared/data", str(data_dir())))
    if argv[:1] != ["motiontrack"]:
        raise ValueError(f"a checked transcript runs motiontrack, got {command!r}")
    out = io.StringIO()
    old = Path.cwd()
    os.chdir(cwd)
    try:
        with contextlib.redirect_stdout(out):
            code = main(argv[1:])
    finally:
        os.chdir(old)
    if code != 0:
        raise RuntimeError(f"{command!r} exited with {code}")
    return out.getvalue()


def _skeleton(line: str) -> str:
    return " ".join(NUMBER.sub("#", line).split())


def _value(text: str) -> float:
    return float(text.replace("−", "-"))


def _half_unit(text: str) -> float:
    """Half a unit in the last digit shown: the rounding ``text`` allows."""
    mantissa, _, exp = text.replace("−", "-").lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 0.5 * 10.0 ** (int(exp or 0) - decimals)


def compare(expected: tuple[str, ...], printed: str) -> list[str]:
    """The differences between the shown lines and the printed output (empty when they agree)."""
    actual = [ln for ln in printed.splitlines() if ln.strip()]
    problems = []
    for shown in expected:
        prefix = shown.rstrip().endswith("...")
        want = _skeleton(shown.rstrip().removesuffix("...").rstrip())
        candidates = [a for a in actual
                      if (_skeleton(a).startswith(want) if prefix else _skeleton(a) == want)]
        if not candidates:
            problems.append(f"not printed: {shown.strip()!r}")
            continue
        numbers = NUMBER.findall(shown.rstrip().removesuffix("..."))
        for cand in candidates:
            got = NUMBER.findall(cand)[:len(numbers)]
            if all(math.isclose(_value(g), _value(n), rel_tol=0, abs_tol=_half_unit(n) + 1e-12)
                   for n, g in zip(numbers, got)):
                break
        else:
            problems.append(f"shown {shown.strip()!r}, printed {candidates[0].strip()!r}")
    return problems


def check(t: Transcript) -> list[str]:
    """Run ``t`` in a scratch folder; the differences found."""
    with tempfile.TemporaryDirectory(prefix="doc-check-") as tmp:
        return compare(t.expected, run(t.command, Path(tmp)))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fast", action="store_true", help="leave out the transcripts marked slow")
    args = ap.parse_args(argv)
    bad = 0
    for t in transcripts():
        if args.fast and t.slow:
            continue
        problems = check(t)
        print(f"{'ok   ' if not problems else 'DRIFT'} {t.where}  {t.command}")
        for p in problems:
            print(f"      {p}")
        bad += bool(problems)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
