"""Output files: written under a temporary name in the same folder, then renamed; the folder
of a run owned by one run at a time.

* A crash or interrupt never leaves a half-written file under the final name; the temporary
  files a killed process leaves are removed by the next run into the folder
  (:func:`remove_leftover_temps`).
* Only regular files are replaced (:func:`check_writable`): never a device, a pipe, a folder or
  a symbolic link. ``-`` (:data:`STDOUT`) is standard output wherever a file name is expected.
* A full device raises :class:`DiskFullError` naming the file; the temporary file is removed,
  and the unwritten data of an :class:`AtomicFile` is kept, so that it can still be committed
  once other outputs have made room.
* :class:`OutputLock` makes a run the only owner of its output folder.
"""

from __future__ import annotations

import contextlib
import errno
import glob
import os
import re
import shutil
import stat
import sys
import tempfile
import time
from pathlib import Path
from typing import IO, Iterable, Iterator

from ..errors import InputError, MotionTrackError

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows: folders are not locked
    fcntl = None

#: the name that means standard output wherever an output file is named
STDOUT = "-"

#: bytes an :class:`AtomicFile` collects before writing them out
BUFFER_SIZE = 1 << 16
#: seconds after which an :class:`AtomicFile`'s next write writes out what it collected, however
#: little: a process that is killed leaves at most about this much of its output unwritten
FLUSH_S = 1.0

#: errno values of a device without room: no space left, quota exceeded
_FULL = {errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC)}


class DiskFullError(MotionTrackError):
    """The device of an output ran out of space (or quota) while ``path`` was written (exit
    code 2, as for any file the machine cannot write)."""

    def __init__(self, path: str | Path, reason: str) -> None:
        self.path = Path(path)
        self.reason = reason
        super().__init__(f"disk full writing {path}: {reason}")

    def __reduce__(self) -> tuple:
        # rebuilt from its arguments: the error of a run in a pool worker reaches the parent
        return (type(self), (self.path, self.reason))


def is_disk_full(exc: BaseException) -> bool:
    """Whether ``exc`` says that the device is full (ENOSPC, EDQUOT)."""
    return isinstance(exc, OSError) and exc.errno in _FULL


def output_error(path: str | Path, exc: OSError) -> OSError | DiskFullError:
    """The error to raise for ``exc`` met while writing ``path``: a :class:`DiskFullError` when
    the device is full, else ``exc`` itself."""
    return DiskFullError(path, exc.strerror or str(exc)) if is_disk_full(exc) else exc


def free_bytes(folder: str | Path) -> int:
    """Bytes this process may still write on the device of ``folder`` (the blocks reserved for
    root count only for root)."""
    if not hasattr(os, "statvfs"):  # pragma: no cover - Windows
        return shutil.disk_usage(folder).free
    st = os.statvfs(folder)
    root = hasattr(os, "geteuid") and os.geteuid() == 0
    return (st.f_bfree if root else st.f_bavail) * st.f_frsize


def is_stdout(path: str | Path | None) -> bool:
    """Whether an output name means standard output (``-``)."""
    return path is not None and str(path) == STDOUT


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: permissions of finished outputs: what ``open()`` would give a new file (0o666 minus the umask)
#: rather than the 0o600 of ``mkstemp``, so other users and web servers can read them as usual
FILE_MODE = 0o666 & ~_current_umask()


def _mkstemp(path: Path, prefix: str, suffix: str) -> tuple[int, Path]:
    """An open descriptor and the name of a new temporary file beside ``path`` (in the system's
    temporary folder for standard output)."""
    folder = None if is_stdout(path) else path.parent
    try:
        fd, tmp = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=folder)
    except OSError as exc:
        raise output_error(path, exc) from None
    try:
        os.fchmod(fd, FILE_MODE)
    except (AttributeError, OSError):  # pragma: no cover - no fchmod (Windows)
        pass
    return fd, Path(tmp)


#: the temporary names of :class:`AtomicFile` and :func:`temp_path_for`: ``.NAME.XXXXXXXX.part``
#: and ``.STEM.XXXXXXXX.part.SUFFIX`` (eight characters of :func:`tempfile.mkstemp`)
_TEMP_NAME = re.compile(r"\.(?P<name>.+)\.[a-z0-9_]{8}\.part(?P<suffix>\.[^.]*)?")


class AtomicFile:
    """A file written under a temporary name beside ``path`` and renamed onto it by
    :meth:`commit`, or removed by :meth:`discard`: for outputs written across many calls.

    Data is collected in memory and written in blocks of :data:`BUFFER_SIZE` bytes, or after
    :data:`FLUSH_S` seconds (what a killed process wrote can be committed later:
    :func:`commit_leftovers`). When the device is full, :meth:`write` raises
    :class:`DiskFullError` and keeps what it could not write, so a later :meth:`commit` (after
    other files made room) still gives the whole file.
    ``mode`` is ``"w"`` (text, written with ``encoding``, newlines as given) or ``"wb"``.
    """

    def __init__(self, path: str | Path, mode: str = "w", encoding: str | None = "utf-8") -> None:
        if mode not in ("w", "wb"):
            raise ValueError(f"an AtomicFile is written from the start ('w' or 'wb'), got {mode!r}")
        self.path = Path(path)
        self.encoding = None if mode == "wb" else (encoding or "utf-8")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._fd: int | None
        self._fd, self.tmp = _mkstemp(self.path, f".{self.path.name}.", ".part")
        self._pending = bytearray()
        self._written = time.monotonic()

    def write(self, data) -> None:
        self._pending += data.encode(self.encoding) if self.encoding else data
        if len(self._pending) >= BUFFER_SIZE or time.monotonic() - self._written >= FLUSH_S:
            self._flush()

    def _flush(self) -> None:
        """Write the collected bytes; on an error the ones not written stay collected."""
        self._written = time.monotonic()
        view = memoryview(self._pending)
        done = 0
        try:
            while done < len(view):
                done += os.write(self._fd, view[done:])
        except OSError as exc:
            raise output_error(self.path, exc) from None
        finally:
            view.release()
            del self._pending[:done]

    def commit(self) -> None:
        """Write what is left, flush to disk and move the file to its final name."""
        try:
            self._flush()
            try:
                os.fsync(self._fd)
                os.close(self._fd)
                self._fd = None
                os.replace(self.tmp, self.path)
            except OSError as exc:
                raise output_error(self.path, exc) from None
        except BaseException:
            self.discard()
            raise

    def discard(self) -> None:
        """Close and remove the temporary file; the final name is left as it was. Never fails:
        it is called while another error is on its way."""
        fd, self._fd = self._fd, None
        self._pending = bytearray()
        if fd is not None:
            with contextlib.suppress(OSError):
                os.close(fd)
        with contextlib.suppress(OSError):
            self.tmp.unlink()


@contextlib.contextmanager
def _stdout(binary: bool) -> Iterator[IO]:
    stream = sys.stdout.buffer if binary else sys.stdout
    yield stream
    stream.flush()


@contextlib.contextmanager
def atomic_open(path: str | Path, mode: str = "w", encoding: str | None = "utf-8") -> Iterator[IO]:
    """A file to ``write`` to under a temporary name next to ``path``, renamed onto ``path``
    when the block succeeds (removed when it fails); ``-`` writes to standard output."""
    if is_stdout(path):
        with _stdout("b" in mode) as stream:
            yield stream
        return
    f = AtomicFile(path, mode, encoding)
    try:
        yield f  # type: ignore[misc]  (it has the ``write`` of a file)
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
    ``cv2.VideoWriter`` that need a real file name); rename it with :func:`commit_temp`. For
    standard output (``-``) the temporary file is in the system's temporary folder."""
    path = Path(path)
    if not is_stdout(path):
        path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = _mkstemp(path, f".{path.stem}.", f".part{path.suffix}")
    os.close(fd)
    return tmp


def commit_temp(tmp: str | Path, path: str | Path) -> None:
    """Move a finished temporary file to its final name (or copy it to standard output and
    remove it)."""
    if not is_stdout(path):
        os.replace(tmp, path)
        return
    try:
        with open(tmp, "rb") as fh, _stdout(binary=True) as out:
            shutil.copyfileobj(fh, out)
    finally:
        Path(tmp).unlink(missing_ok=True)


def _kind(path: Path) -> str | None:
    """What is at ``path`` (without following a symbolic link), or None when nothing is."""
    try:
        mode = os.lstat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):
        return None
    for test, kind in ((stat.S_ISREG, "a regular file"), (stat.S_ISDIR, "a folder"),
                       (stat.S_ISLNK, "a symbolic link"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a named pipe"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return kind
    return "a special file"  # pragma: no cover


def check_writable(paths: Iterable[str | Path], force: bool) -> None:
    """Refuse to overwrite existing outputs unless ``force``, and refuse always to replace
    anything but a regular file (a device, a named pipe, a folder, a symbolic link: replacing
    one would turn ``/dev/full`` into a file). ``-`` (standard output) is always writable."""
    existing = []
    for p in paths:
        if is_stdout(p):
            continue
        kind = _kind(Path(p))
        if kind is None:
            continue
        if kind != "a regular file":
            hint = "" if kind == "a folder" else "; use - for standard output"
            raise InputError(f"output {p} is {kind}, not a regular file: only regular files are "
                             f"replaced{hint}")
        existing.append(str(p))
    if existing and not force:
        raise InputError(
            f"output exists: {', '.join(existing)} (use --force to overwrite)"
        )


def remove_outputs(paths: Iterable[str | Path], folders: Iterable[str | Path] = ()) -> None:
    """Remove old outputs before a forced run writes new ones, so that old and new never mix:
    the regular files among ``paths`` and the whole of each of ``folders`` (a symbolic link is
    removed, not followed). Anything else at one of ``paths`` is refused as in
    :func:`check_writable`."""
    paths = [Path(p) for p in paths if not is_stdout(p)]
    check_writable(paths, force=True)
    for p in paths:
        with contextlib.suppress(FileNotFoundError):
            p.unlink()
    for d in map(Path, folders):
        kind = _kind(d)
        if kind == "a folder":
            shutil.rmtree(d)
        elif kind is not None:
            d.unlink()


def remove_leftover_temps(paths: Iterable[str | Path]) -> list[Path]:
    """Remove the temporary files of the outputs ``paths`` that a killed run left behind (a
    process killed by SIGKILL cannot remove them); returns them.

    Only the names this module gives the temporary files of these outputs are touched
    (``.NAME.XXXXXXXX.part`` and ``.STEM.XXXXXXXX.part.SUFFIX``). Call it while holding the
    folder's :class:`OutputLock`: no other run is writing them then.
    """
    removed = []
    for p in map(Path, paths):
        if is_stdout(p) or not p.parent.is_dir():
            continue
        for prefix in {p.name, p.stem}:
            for q in p.parent.glob(glob.escape(f".{prefix}.") + "*.part*"):
                m = _TEMP_NAME.fullmatch(q.name)
                if (m and (m["name"], m["suffix"] or "") in ((p.name, ""), (p.stem, p.suffix))
                        and _kind(q) == "a regular file"):
                    q.unlink(missing_ok=True)
                    removed.append(q)
    return removed


def remove_folder_temps(folder: str | Path) -> list[Path]:
    """Remove every temporary file this module's writers left in ``folder`` (the names of
    :func:`remove_leftover_temps`, whatever output they were for: a killed run may have written
    a video the next run does not write); returns them. Call it while holding the folder's
    :class:`OutputLock`."""
    folder = Path(folder)
    removed = []
    if not folder.is_dir():
        return removed
    for q in folder.glob(".*.part*"):
        if _TEMP_NAME.fullmatch(q.name) and _kind(q) == "a regular file":
            q.unlink(missing_ok=True)
            removed.append(q)
    return removed


@contextlib.contextmanager
def writing_outputs(paths: Iterable[str | Path], force: bool) -> Iterator[None]:
    """For a command writing a few files (``evaluate --json``, ``synth-events``): hold the
    :class:`OutputLock` of the folder of each output while the block runs (refused at once when
    a run holds one, as a second run into a folder is), remove the temporary files a killed
    writer left of these outputs, and :func:`check_writable` them. ``-`` (standard output) has
    no folder."""
    paths = [Path(p) for p in paths if not is_stdout(p)]
    folders = sorted({Path(os.path.abspath(p)).parent for p in paths})
    with contextlib.ExitStack() as stack:
        for folder in folders:
            stack.enter_context(OutputLock(folder))
        remove_leftover_temps(paths)
        check_writable(paths, force)
        yield


#: outputs made of lines: what a killed writer left is kept up to its last whole line
LINE_SUFFIXES = frozenset({".txt", ".jsonl", ".csv"})
#: outputs that play as far as they were written (WebM/Matroska is written as it goes)
STREAM_SUFFIXES = frozenset({".webm", ".mkv"})


def commit_leftovers(folder: str | Path) -> list[Path]:
    """Commit, under their final names, the temporary files a killed writer left in ``folder``
    (the names this module gives them) where the final name is free; returns the final paths.

    Files of lines (:data:`LINE_SUFFIXES`) are kept up to their last whole line, a WebM or
    Matroska video as written (it plays up to the last frame written); an empty one is removed.
    The others (a picture or a summary written in one go, an MP4 whose index comes last) are
    useless cut short and are left as they are. Call it while no process writes into ``folder``.
    """
    folder = Path(folder)
    kept = []
    for q in sorted(folder.glob(".*.part*")):
        m = _TEMP_NAME.fullmatch(q.name)
        if m is None or _kind(q) != "a regular file":
            continue
        final = folder / (m["name"] + (m["suffix"] or ""))
        if os.path.lexists(final):
            continue
        suffix = final.suffix.lower()
        if suffix in LINE_SUFFIXES:
            data = q.read_bytes()
            whole = data[:data.rfind(b"\n") + 1]
            if len(whole) < len(data):
                with open(q, "r+b") as fh:
                    fh.truncate(len(whole))
        elif suffix not in STREAM_SUFFIXES:
            continue
        if q.stat().st_size == 0:
            q.unlink()
            continue
        os.replace(q, final)
        kept.append(final)
    return kept


class OutputLock:
    """One run at a time in an output folder: an exclusive ``fcntl.flock`` on
    ``FOLDER/.motiontrack.lock``, taken at once or refused with :class:`InputError` naming the
    folder (and the process that holds it). The folder is created when missing.

    :meth:`release` (also on leaving a ``with`` block, or when the lock is garbage-collected)
    removes the file, frees the lock and removes the folder again, with the parents it created,
    when the lock created it and nothing was written; the system frees the lock of a process that
    dies, so a killed run never blocks the next one.
    """

    NAME = ".motiontrack.lock"

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.path = self.folder / self.NAME
        self._fd: int | None = None
        #: the folders the lock creates, the deepest first
        self._created = [p for p in (self.folder, *self.folder.parents) if not p.exists()]
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except (FileExistsError, NotADirectoryError):
            raise InputError(f"output folder {self.folder} is not a folder") from None
        except OSError as exc:
            raise InputError(f"cannot create output folder {self.folder}: "
                             f"{exc.strerror or exc}") from None
        if fcntl is not None:
            self._acquire()

    def _acquire(self) -> None:
        for _ in range(100):  # the holder may remove the file between our open and our lock
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            except FileNotFoundError:  # another run's lock removed the empty folder it made
                self.folder.mkdir(parents=True, exist_ok=True)
                continue
            except OSError as exc:
                raise InputError(f"cannot write to output folder {self.folder}: "
                                 f"{exc.strerror or exc}") from None
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = _read_pid(fd)
                os.close(fd)
                raise InputError(
                    f"output folder {self.folder} is in use by another motiontrack run"
                    f"{f' (process {holder})' if holder else ''}; wait for it to end or choose "
                    "another folder") from None
            except OSError:  # pragma: no cover - a file system without locks: run unlocked
                os.close(fd)
                return
            try:
                same = os.path.samestat(os.fstat(fd), os.stat(self.path))
            except FileNotFoundError:
                same = False
            if same:
                self._fd = fd
                with contextlib.suppress(OSError):  # the pid is informative only (a full disk)
                    os.ftruncate(fd, 0)
                    os.write(fd, f"{os.getpid()}\n".encode())
                return
            os.close(fd)
        raise InputError(f"cannot lock output folder {self.folder}")  # pragma: no cover

    def release(self) -> None:
        """Remove the lock file and free the lock (harmless when already released)."""
        fd, self._fd = self._fd, None
        if fd is None:
            return
        with contextlib.suppress(OSError):  # removed while held: the next run locks a new file
            os.unlink(self.path)
        os.close(fd)
        for p in self._created:
            try:
                p.rmdir()   # only when empty
            except OSError:
                break

    def __enter__(self) -> "OutputLock":
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def __del__(self) -> None:
        with contextlib.suppress(Exception):
            self.release()


def _read_pid(fd: int) -> str:
    with contextlib.suppress(OSError, ValueError):
        text = os.pread(fd, 32, 0).decode("ascii").strip()
        if text.isdigit():
            return text
    return ""
