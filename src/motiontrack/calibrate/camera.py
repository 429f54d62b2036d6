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

import logging
from pathlib import Path
from typing import Protocol, Union

import numpy as np


from ..errors import InputError, excerpt, location, require_file
from ..io.tomlfile import read_toml
from .chessboard import OpenCVCamera, read_opencv_yaml
from .ground import GroundHomography, ground_from_toml_doc
from .tsai import TsaiCamera, _kind, read_tsai_xml, tsai_from_toml_doc

__all__ = ["Camera", "load_camera", "AnyCamera", "fit_to_image"]

log = logging.getLogger(__name__)

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


def fit_to_image(camera: AnyCamera, width: int, height: int, name: str) -> AnyCamera:
    """``camera`` (read from the file ``name``) for a video of ``width`` x ``height`` pixels.

    A camera is calibrated on images of one size, which its file states (Tsai XML and TOML:
    ``width``/``height``; OpenCV YAML: ``image_width``/``image_height``; a homography TOML: the
    optional ``width``/``height``). A video of that size uses it as it is. A scaled copy of the
    video (the same aspect ratio, within a pixel of rounding) gets the camera scaled to it
    (:meth:`~.tsai.TsaiCamera.resized`), with a warning; any other size is an
    :class:`InputError` naming both, since a cropped or padded picture has no such map. A
    homography that states no size is used as it is (nothing to check it against).
    """
    size = camera.image_size
    if size is None:
        log.info("camera %s states no image size: taken to be calibrated on %dx%d frames",
                 name, width, height)
        return camera
    cw, ch = size
    if (cw, ch) == (width, height):
        return camera
    # the same picture scaled: each side within a pixel of the other side's scale
    if not (abs(width - cw * height / ch) <= 1.0 or abs(height - ch * width / cw) <= 1.0):
        raise InputError(f"camera {location(name)} is calibrated on {cw}x{ch} images but the "
                         f"video is {width}x{height}, another aspect ratio (cropped or padded); "
                         "calibrate the camera on this video's frames")
    log.warning("camera %s is calibrated on %dx%d images; the video is %dx%d: scaling the "
                "camera by %.4g x %.4g", name, cw, ch, width, height, width / cw, height / ch)
    return camera.resized(width, height)
