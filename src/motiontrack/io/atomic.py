"""Atomic output files: write to a temporary name in the same folder, then rename.

A crash or interrupt never leaves a half-written file under the final name.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path
from typing import IO, Iterator

from ..errors import InputError


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: permissions of finished outputs: what ``open()`` would give a new file (0o666 minus the umask)
#: rather than the 0o600 of ``mkstemp``, so other users and web servers can read them as usual
FILE_MODE = 0o666 & ~_current_umask()


def _mkstemp(path: Path, prefix: str, suffix: str) -> Path:
    fd, tmp = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=path.parent)
    try:
        os.fchmod(fd, FILE_MODE)
    except (AttributeError, OSError):  # pragma: no cover - no fchmod (Windows)
        pass
    finally:
        os.close(fd)
    return Path(tmp)


def _tmp_path(path: Path) -> Path:
    return _mkstemp(path, f".{path.name}.", ".part")


class AtomicFile:
    """A file written under a temporary name beside ``path`` and renamed onto it by
    :meth:`commit`, or removed by :meth:`discard`: for outputs written across many calls."""

    def __init__(self, path: str | Path, mode: str = "w", encoding: str | None = "utf-8") -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.tmp = _tmp_path(self.path)
        try:
            self.fh: IO = open(self.tmp, mode, encoding=None if "b" in mode else encoding)
        except BaseException:
            self.tmp.unlink(missing_ok=True)
            raise

    def write(self, data) -> None:
        self.fh.write(data)

    def commit(self) -> None:
        """Flush to disk and move the file to its final name."""
        try:
            self.fh.flush()
            os.fsync(self.fh.fileno())
            self.fh.close()
            os.replace(self.tmp, self.path)
        except BaseException:
            self.discard()
            raise

    def discard(self) -> None:
        """Close and remove the temporary file; the final name is left as it was."""
        self.fh.close()
        with contextlib.suppress(FileNotFoundError):
            self.tmp.unlink()


@contextlib.contextmanager
def atomic_open(path: str | Path, mode: str = "w", encoding: str | None = "utf-8") -> Iterator[IO]:
    """Open a temporary file next to ``path``; rename onto ``path`` when the block succeeds."""
    f = AtomicFile(path, mode, encoding)
    try:
        yield f.fh
    except BaseException:
        f.discard()
        raise
    f.commit()


def atomic_write_text(path: str | Path, text: str) -> None:
    with atomic_open(path, "w") as fh:
        fh.write(text)


def atomic_write_bytes(path: str | Path, data: bytes) -> None:
    with atomic_open(path, "wb") as fh:
        fh.write(data)


def temp_path_for(path: str | Path) -> Path:
    """A fresh temporary path beside ``path`` with the same suffix (for writers such as
    ``cv2.VideoWriter`` that need a real file name); rename it with :func:`commit_temp`."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return _mkstemp(path, f".{path.stem}.", f".part{path.suffix}")


def commit_temp(tmp: str | Path, path: str | Path) -> None:
    os.replace(tmp, path)


def check_writable(paths: list[Path], force: bool) -> None:
    """Refuse to overwrite existing outputs unless ``force``."""
    existing = [str(p) for p in paths if p.exists()]
    if existing and not force:
        raise InputError(
            f"output exists: {', '.join(existing)} (use --force to overwrite)"
        )
