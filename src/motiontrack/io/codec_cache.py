"""The names of the codecs this installation encodes, for the ``--codec`` help, without loading
OpenCV or PyAV on every ``--help``.

Probing (:func:`motiontrack.io.video.encodable_codecs`) imports OpenCV and PyAV and opens each
encoder: about a third of a second, twice what the rest of ``motiontrack track --help`` takes.
Its answer depends only on the installation, so it is kept in a small JSON file under the user's
cache folder (``$XDG_CACHE_HOME/motiontrack``, default ``~/.cache/motiontrack``), named after
what it depends on: the interpreter, motiontrack's version and its ``io/video.py``, and the
files of the installed ``cv2`` and ``av`` packages (path, size, modification time). Installing
another OpenCV or PyAV therefore probes again. A process that has already loaded the video
module probes anyway (its probes are cached in memory and cost no imports there), and a cache
folder that cannot be read or written only means probing each time.
"""

from __future__ import annotations

import importlib.util
import json
import logging
import os
import sys
import tempfile
import zlib
from pathlib import Path

from ..version import __version__

log = logging.getLogger(__name__)

#: the packages whose builds decide what can be encoded
_PROBED_PACKAGES = ("cv2", "av")


def encodable_codec_names() -> list[str]:
    """The names :func:`~motiontrack.io.video.encodable_codecs` gives, in its order: from the
    cache file of this installation when there is one, else probed (and the cache written)."""
    video = sys.modules.get(f"{__package__}.video")
    if video is not None:
        return list(video.encodable_codecs())
    key = installation_key()
    path = cache_file(key)
    if path is not None:
        names = _read(path, key)
        if names is not None:
            return names
    from .video import encodable_codecs

    names = list(encodable_codecs())
    if path is not None:
        _write(path, key, names)
    return names


def installation_key() -> dict[str, object]:
    """What the probe's answer depends on (see the module's description)."""
    return {"python": sys.version, "prefix": sys.prefix, "motiontrack": __version__,
            "video.py": _file_state(Path(__file__).with_name("video.py")),
            **{name: _package_state(name) for name in _PROBED_PACKAGES}}


def cache_file(key: dict[str, object]) -> Path | None:
    """The cache file of ``key``; None when there is no home or cache folder to put it in."""
    root = os.environ.get("XDG_CACHE_HOME")
    try:
        folder = Path(root) if root else Path.home() / ".cache"
    except RuntimeError:   # no home folder known
        return None
    # the file holds its key too: two keys of one name only take turns in it
    digest = zlib.crc32(json.dumps(key, sort_keys=True).encode())
    return folder / "motiontrack" / f"codecs-{digest:08x}.json"


def _file_state(path: Path) -> list[object] | None:
    try:
        st = path.stat()
    except OSError:
        return None
    return [str(path), st.st_size, st.st_mtime_ns]


def _package_state(name: str) -> list[object] | None:
    """Where ``name`` is installed and the state of its files (the module itself, or a
    package's ``__init__`` and folder), found without importing it; None when absent."""
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return None
    if spec is None or spec.origin is None:
        return None
    origin = Path(spec.origin)
    state = [_file_state(origin)]
    if spec.submodule_search_locations:
        state.append(_file_state(origin.parent))
    return state


def _read(path: Path, key: dict[str, object]) -> list[str] | None:
    try:
        stored = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(stored, dict) or stored.get("key") != json.loads(json.dumps(key)):
        return None
    names = stored.get("codecs")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        return None
    return names


def _write(path: Path, key: dict[str, object], names: list[str]) -> None:
    """Write the cache file under a temporary name and rename it, so that a concurrent reader
    sees the old file or the whole new one."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".codecs-", suffix=".json", dir=path.parent)
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                json.dump({"key": key, "codecs": names}, f)
            os.replace(tmp, path)
        except BaseException:
            os.unlink(tmp)
            raise
    except OSError as exc:
        log.debug("codec list not cached in %s: %s", path, exc)
