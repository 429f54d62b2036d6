"""Camera calibration and measurements in metres (see ``docs/calibration.md``).

* :mod:`.tsai` — Tsai's model with the PETS 2009 XML layout and our TOML;
* :mod:`.chessboard` — OpenCV chessboard calibration and OpenCV-compatible YAML;
* :mod:`.lines` — the thesis' method: κ1 by straight lines, sub-pixel lines, coplanar Tsai fit;
* :mod:`.ground` — ground-plane homography from point pairs;
* :mod:`.camera` — :func:`load_camera` for any of these files, :func:`fit_to_image` for the
  video's size;
* :mod:`.measure` — world positions, speeds, path lengths and heights of tracks.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from .camera import fit_to_image, load_camera
    from .measure import track_measurements, world_positions

__all__ = ["fit_to_image", "load_camera", "track_measurements", "world_positions"]


def __getattr__(name: str) -> Any:
    # each submodule loads when one of its names is first used: measurements (NumPy only) need
    # none of the camera files' readers (XML, YAML, OpenCV calibration)
    if name in ("fit_to_image", "load_camera"):
        from . import camera as module
    elif name in ("track_measurements", "world_positions"):
        from . import measure as module
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(module, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
