"""The MOTChallenge benchmark layout, as TrackEval's ``MotChallenge2DBox`` reads it.

::

    SPLIT/<seq>/gt/gt.txt            ground truth of one sequence
    SPLIT/<seq>/seqinfo.ini          [Sequence] seqLength = number of frames
    SPLIT/<seq>/det/det.txt          public detections of one sequence
    TRACKERS/<tracker>/data/<seq>.txt   one tracker's result for that sequence

A seqmap file (TrackEval's ``seqmaps/MOT17-train.txt``) lists the sequences to evaluate: a header
line (``name``), then one sequence per line (only the first comma-separated field counts).
Without one, every folder of ``SPLIT`` that holds ``gt/`` or ``seqinfo.ini`` is a sequence.

Only paths and sequence lengths are found here; reading the files is
:func:`motiontrack.io.mot.read_mot`'s work.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError, excerpt, location, printable
from .mot import read_seqinfo

__all__ = ["LayoutSequence", "read_seqmap", "split_sequences", "tracker_names", "tracker_file",
           "seqinfo_for", "detection_files"]

#: the folder of a tracker holding its result files (TrackEval ``TRACKER_SUB_FOLDER``)
TRACKER_SUB_FOLDER = "data"


@dataclass(frozen=True)
class LayoutSequence:
    """One sequence of a split: its name, ground-truth file and length in frames."""

    name: str
    gt_path: Path
    length: int


def read_seqmap(path: str | Path) -> list[str]:
    """Sequence names of a seqmap file: the first field of every line after the header, blank
    lines skipped, each name once (in file order)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"seqmap file not found: {location(p)}")
    try:
        text = p.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{location(p)}: not a text file ({exc.reason} at byte {exc.start})") \
            from None
    names: list[str] = []
    for lineno, row in enumerate(csv.reader(io.StringIO(text)), start=1):
        if lineno == 1 or not row or not row[0].strip():
            continue
        name = row[0].strip()
        if name in (".", "..") or "/" in name or "\\" in name:
            raise InputError(f"{location(p, lineno)}: not a sequence name: {excerpt(name)}")
        if name not in names:
            names.append(name)
    if not names:
        raise InputError(f"{location(p)}: no sequences (a header line, then one name per line)")
    return names


def _sequence_length(folder: Path) -> int:
    ini = folder / "seqinfo.ini"
    if not ini.is_file():
        # TrackEval: "ini file does not exist" — the length cannot be guessed from the files
        raise InputError(f"sequence {printable(folder.name)}: seqinfo.ini not found: {location(ini)}")
    info = read_seqinfo(ini)
    length = info.get("seqlength")
    if not isinstance(length, int) or length < 1:
        raise InputError(f"{location(ini)}: [Sequence] seqLength must be a whole number >= 1, "
                         f"got {excerpt(str(length)) if length is not None else 'nothing'}")
    return length


def split_sequences(gt_folder: str | Path, seqmap: str | Path | None = None) -> list[LayoutSequence]:
    """The sequences of a split folder, sorted by name (the order TrackEval evaluates and
    combines them in), each with its ``gt/gt.txt`` and ``seqLength``.

    Raises
    ------
    InputError
        The folder, a listed sequence, its ``gt/gt.txt`` or ``seqinfo.ini`` is missing, or the
        split holds no sequence.
    """
    root = Path(gt_folder)
    if not root.is_dir():
        raise InputError(f"ground-truth folder not found: {location(root)}")
    if seqmap is not None:
        names = read_seqmap(seqmap)
        missing = [n for n in names if not (root / n).is_dir()]
        if missing:
            raise InputError(f"sequence {excerpt(missing[0])} of the seqmap not found in "
                             f"{location(root)}")
    else:
        names = [d.name for d in root.iterdir()
                 if d.is_dir() and not d.name.startswith(".")
                 and ((d / "gt").is_dir() or (d / "seqinfo.ini").is_file())]
        if not names:
            raise InputError(f"no sequences in {location(root)} (expected <seq>/gt/gt.txt and "
                             f"<seq>/seqinfo.ini)")
    out = []
    for name in sorted(names):
        gt = root / name / "gt" / "gt.txt"
        if not gt.is_file():
            raise InputError(f"ground-truth file not found for sequence {printable(name)}: "
                             f"{location(gt)}")
        out.append(LayoutSequence(name, gt, _sequence_length(root / name)))
    return out


def tracker_names(trackers_folder: str | Path) -> list[str]:
    """Every tracker of a trackers folder: its sub-folders (hidden ones left out), sorted."""
    root = Path(trackers_folder)
    if not root.is_dir():
        raise InputError(f"trackers folder not found: {location(root)}")
    names = sorted(d.name for d in root.iterdir() if d.is_dir() and not d.name.startswith("."))
    if not names:
        raise InputError(f"no trackers in {location(root)} (expected <tracker>/"
                         f"{TRACKER_SUB_FOLDER}/<seq>.txt)")
    return names


def tracker_file(trackers_folder: str | Path, tracker: str, sequence: str) -> Path:
    """``TRACKERS/<tracker>/data/<sequence>.txt``; a missing one is TrackEval's error."""
    p = Path(trackers_folder) / tracker / TRACKER_SUB_FOLDER / f"{sequence}.txt"
    if not p.is_file():
        raise InputError(f"Tracker file not found: "
                         f"{printable(tracker)}/{TRACKER_SUB_FOLDER}/{printable(p.name)} "
                         f"({location(p)})")
    return p


def seqinfo_for(det_path: str | Path) -> Path | None:
    """The ``seqinfo.ini`` of a detections file: beside it, or in the folder above, as
    MOTChallenge lays a sequence out (``SEQ/seqinfo.ini``, ``SEQ/det/det.txt``); None when
    there is neither."""
    folder = Path(det_path).parent
    for d in (folder, folder.parent):
        if (d / "seqinfo.ini").is_file():
            return d / "seqinfo.ini"
    return None


def detection_files(split: str | Path) -> list[tuple[str, Path]]:
    """``(sequence, SPLIT/<seq>/det/det.txt)`` for every sequence of a split folder that has
    one, sorted by name.

    Raises
    ------
    InputError
        The folder is missing, or no sequence in it has ``det/det.txt``.
    """
    root = Path(split)
    if not root.is_dir():
        raise InputError(f"detections folder not found: {location(root)}")
    found = sorted((d.name, d / "det" / "det.txt") for d in root.iterdir()
                   if d.is_dir() and not d.name.startswith(".")
                   and (d / "det" / "det.txt").is_file())
    if not found:
        raise InputError(f"no sequences with detections in {location(root)} (expected "
                         f"<seq>/det/det.txt)")
    return found
