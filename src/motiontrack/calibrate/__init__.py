"""Camera calibration and measurements in metres (see ``docs/calibration.md``).

* :mod:`.tsai` — Tsai's model with the PETS 2009 XML layout and our TOML;
* :mod:`.chessboard` — OpenCV chessboard calibration and OpenCV-compatible YAML;
* :mod:`.lines` — the thesis' method: κ1 by straight lines, sub-pixel lines, coplanar Tsai fit;
* :mod:`.ground` — ground-plane homography from point pairs;
* :mod:`.camera` — :func:`load_camera` for any of these files, :func:`fit_to_image` for the
  video's size;
* :mod:`.measure` — world positions, speeds, path lengths and heights of tracks.
"""

from .camera import fit_to_image, load_camera
from .measure import track_measurements, world_positions

__all__ = ["fit_to_image", "load_camera", "track_measurements", "world_positions"]
