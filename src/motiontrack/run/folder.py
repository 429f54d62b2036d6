"""The folder of one run: the names of its outputs, its ``summary.json``, what it says of the
source (frame rate, frame size), the salvage of a run killed before it wrote its summary, and
the ``.NAME.partial`` folder a batch run writes into before it is renamed into place.

Every writer and reader of a run folder goes through :class:`RunFolder`, so that the names of
the files and the keys read from ``summary.json`` are written down once.
"""

from __future__ import annotations

import hashlib
import json
import math
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..io.atomic import OutputLock, atomic_write_text, commit_leftovers
from ..io.event_store import STORE_NAME
from ..io.mot import read_seqinfo

__all__ = ["RunFolder"]


@dataclass(frozen=True)
class RunFolder:
    """The folder ``path`` of one run (it need not exist yet)."""

    path: Path

    def __post_init__(self) -> None:
        object.__setattr__(self, "path", Path(self.path))

    # ------------------------------------------------------------------ output names
    TRACKS = "tracks.txt"
    SUMMARY = "summary.json"
    CONFIG = "config.toml"
    EVENTS = "events.jsonl"
    EVENT_STORE = STORE_NAME
    COUNTS = "counts.csv"
    GT = "gt.txt"
    HEATMAP = "heatmap.png"
    HEATMAP_WORLD = "heatmap_world.png"
    LOCK = OutputLock.NAME

    @classmethod
    def beside(cls, path: str | Path) -> "RunFolder":
        """The run folder holding the file ``path`` (a tracks file, typically)."""
        return cls(Path(path).resolve().parent)

    @property
    def tracks(self) -> Path:
        return self.path / self.TRACKS

    @property
    def summary_path(self) -> Path:
        return self.path / self.SUMMARY

    @property
    def config(self) -> Path:
        return self.path / self.CONFIG

    @property
    def events(self) -> Path:
        return self.path / self.EVENTS

    @property
    def event_store(self) -> Path:
        return self.path / self.EVENT_STORE

    @property
    def counts(self) -> Path:
        return self.path / self.COUNTS

    @property
    def gt(self) -> Path:
        return self.path / self.GT

    @property
    def heatmap(self) -> Path:
        return self.path / self.HEATMAP

    @property
    def heatmap_world(self) -> Path:
        return self.path / self.HEATMAP_WORLD

    def heatmap_of(self, label: str) -> Path:
        """The heat map of the tracks of one class (``--by-class``): ``heatmap_person.png``."""
        return self.path / f"heatmap_{label}.png"

    # ----------------------------------------------------------------------- summary
    def has_summary(self) -> bool:
        return self.summary_path.exists()

    def summary(self) -> dict[str, Any] | None:
        """The run's ``summary.json`` as a dict, or None when it is absent or unreadable."""
        return self.read_summary()[0]

    def read_summary(self) -> tuple[dict[str, Any] | None, str]:
        """The run's ``summary.json`` as a dict and ``""``, or None and what is wrong with it
        (``""`` when there is none): not UTF-8, not JSON, nested too deeply, not an object."""
        try:
            doc = json.loads(self.summary_path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            return None, ""
        except OSError as exc:
            return None, f"cannot be read ({exc.strerror or exc})"
        except RecursionError:
            return None, "nested too deeply"
        except ValueError as exc:   # not UTF-8, not JSON
            return None, f"malformed ({str(exc).splitlines()[0] if str(exc) else 'not JSON'})"
        return (doc, "") if isinstance(doc, dict) else (None, "not a JSON object")

    # ------------------------------------------------------------------ output digests
    def digests(self) -> dict[str, dict[str, Any]]:
        """``{name: {"bytes": size, "sha256": hex digest}}`` of the run's outputs: the regular
        files of the folder but ``summary.json`` (which records them) and hidden ones."""
        out: dict[str, dict[str, Any]] = {}
        for p in sorted(self.path.iterdir()):
            if p.name.startswith(".") or p.name == self.SUMMARY or p.is_symlink() \
                    or not p.is_file():
                continue
            out[p.name] = {"bytes": p.stat().st_size, "sha256": _sha256(p)}
        return out

    def changed(self, digests: Any) -> str:
        """What differs between the folder and ``digests`` (as :meth:`digests` gives them):
        ``""`` when every recorded output is there with its size and content, else the first
        difference (``"tracks.txt is missing"``, ``"tracks.txt changed"``)."""
        if not isinstance(digests, dict) or not digests:
            return "no record of its outputs"
        for name, rec in sorted(digests.items()):
            p = self.path / str(name)
            if not isinstance(rec, dict) or Path(str(name)).name != name:
                return "a malformed record of its outputs"
            if p.is_symlink() or not p.is_file():
                return f"{name} is missing"
            if p.stat().st_size != rec.get("bytes") or _sha256(p) != rec.get("sha256"):
                return f"{name} changed"
        return ""

    def write_summary(self, summary: dict[str, Any]) -> Path:
        """Write ``summary.json`` atomically (indented JSON, one trailing newline)."""
        atomic_write_text(self.summary_path, json.dumps(summary, indent=2) + "\n")
        return self.summary_path

    # ---------------------------------------------------------- what the run states
    def frame_rate(self) -> float | None:
        """The frame rate the folder states: ``summary.json``'s ``source_fps``, or a
        MOTChallenge ``seqinfo.ini`` in the folder or the one above (``gt/gt.txt``); ``None``
        when neither does."""
        fps = (self.summary() or {}).get("source_fps")
        if isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0:
            return float(fps)
        info = self._seqinfo()
        if info is None:
            return None
        fps = info.get("framerate")   # the reader lower-cases keys
        return float(fps) if isinstance(fps, (int, float)) and fps > 0 else None

    def frame_size(self) -> tuple[int, int] | None:
        """``(width, height)`` of the frames the folder states: ``summary.json``, or a
        MOTChallenge ``seqinfo.ini`` (``imWidth``, ``imHeight``) in the folder or the one above;
        ``None`` when neither does."""
        doc = self.summary() or {}
        w, h = doc.get("width"), doc.get("height")
        if isinstance(w, int) and isinstance(h, int) and w > 0 and h > 0:
            return w, h
        info = self._seqinfo()
        if info is None:
            return None
        w, h = info.get("imwidth"), info.get("imheight")
        return (w, h) if isinstance(w, int) and isinstance(h, int) and w > 0 and h > 0 else None

    def _seqinfo(self) -> dict[str, Any] | None:
        """The first ``seqinfo.ini`` of the folder and the one above; None when there is none
        or it cannot be read."""
        for d in (self.path, self.path.parent):
            if (d / "seqinfo.ini").is_file():
                try:
                    return read_seqinfo(d)
                except InputError:
                    return None
        return None

    # ------------------------------------------------------------------------ salvage
    def salvage(self, source: str, status: dict[str, Any], code: int | None) -> bool:
        """Commit what a killed run left in the folder when it has no ``summary.json``: the
        files of lines written so far (up to the last whole line;
        :func:`~motiontrack.io.atomic.commit_leftovers`) under their names, and a
        ``summary.json`` that says so (``"status": "killed (exit code N)"``, ``"truncated":
        true``, the frame size and rate from ``status``, so that the folder reads as a finished
        run's). Call it while no process writes into the folder. Returns whether anything was
        committed."""
        if self.has_summary():
            return False
        kept = commit_leftovers(self.path)
        if not kept:
            return False
        self.write_summary({
            "source": source, "width": status.get("width"), "height": status.get("height"),
            "source_fps": status.get("source_fps"), "status": f"killed (exit code {code})",
            "interrupted": True, "truncated": True,
            "outputs": {p.name.split(".")[0]: str(p) for p in kept}})
        return True

    # ---------------------------------------------------------------- partial folder
    def partial(self) -> "RunFolder":
        """The hidden folder ``.NAME.partial`` beside this one, written before the run is
        complete and renamed into place by :meth:`commit_partial`."""
        return RunFolder(self.path.parent / f".{self.path.name}.partial")

    def remove(self) -> None:
        """Remove the folder and everything in it (nothing when it does not exist)."""
        shutil.rmtree(self.path, ignore_errors=True)

    def commit_partial(self, extra: dict[str, Any]) -> None:
        """Rename :meth:`partial` into place as this folder: its summary's outputs renamed to
        the paths they have here and ``extra`` added to it; an existing folder is replaced (it
        goes as the new one arrives)."""
        part = self.partial()
        meta = part.summary() or {}
        meta["outputs"] = {k: str(self.path / Path(p).name)
                           for k, p in meta.get("outputs", {}).items()}
        meta.update(extra)
        part.write_summary(meta)
        if self.path.exists():   # a redone run: the old folder goes as the new one arrives
            old = RunFolder(self.path.parent / f".{self.path.name}.old")
            old.remove()
            self.path.rename(old.path)
            part.path.rename(self.path)
            old.remove()
        else:
            part.path.rename(self.path)


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()
