"""One entry point for every camera file: :func:`load_camera`.

All cameras answer the same questions in the same units:

* ``image_to_world(points (N, 2) px) -> (N, 2)`` metres on the ground plane ``Z = 0``;
* ``world_to_image(points (N, 2|3) metres, distorted=True) -> (N, 2)`` pixels;
* ``undistort(image) -> image``;
* ``rays(points) -> (origins, directions)`` (Tsai and posed OpenCV cameras only; needed for heights).

File kinds, by content: PETS/Tsai XML (``.xml``), OpenCV ``FileStorage`` YAML (``.yml``/``.yaml``)
and our TOML (``model = "tsai"`` or ``model = "homography"``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol, Union

import numpy as np


from ..errors import InputError, excerpt, location, require_file
from ..io.tomlfile import read_toml
from .chessboard import OpenCVCamera, read_opencv_yaml
from .ground import GroundHomography, ground_from_toml_doc
from .tsai import TsaiCamera, _kind, read_tsai_xml, tsai_from_toml_doc

__all__ = ["Camera", "load_camera", "AnyCamera"]

AnyCamera = Union[TsaiCamera, OpenCVCamera, GroundHomography]


class Camera(Protocol):
    def image_to_world(self, pixels: np.ndarray) -> np.ndarray: ...

    def world_to_image(self, points: np.ndarray, distorted: bool = True) -> np.ndarray: ...

    def undistort(self, image: np.ndarray) -> np.ndarray: ...


def load_camera(path: str | Path) -> AnyCamera:
    """Read any supported camera file; raises :class:`InputError` on a missing/malformed file."""
    p = require_file(path, "camera file")
    suffix = p.suffix.lower()
    if suffix == ".xml":
        return read_tsai_xml(p)
    if suffix in (".yml", ".yaml"):
        return read_opencv_yaml(p)
    if suffix == ".toml":
        doc = read_toml(p, "camera TOML")
        model = doc.get("model")
        if model == "tsai":
            return tsai_from_toml_doc(doc, str(p))
        if model == "homography":
            return ground_from_toml_doc(doc, str(p))
        shown = excerpt(model) if isinstance(model, str) else _kind(model)
        raise InputError(f"{location(p)}: model must be 'tsai' or 'homography', got {shown}")
    raise InputError(f"{location(p)}: unknown camera file type {excerpt(suffix)} (expected .xml, "
                     ".yml/.yaml or .toml)")
