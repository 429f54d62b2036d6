"""BGSLibrary's background models as a motion method (``motion.method = "bgslibrary"``).

BGSLibrary (A. Sobral, https://github.com/andrewssobral/bgslibrary) gathers the background
models this field reaches for when accuracy matters more than CPU: SuBSENSE and PAWCS (St-Charles
et al.), LOBSTER, ViBe, codebooks, fuzzy and SOM models. Its Python binding ``pybgs`` builds from
source (the ``bgslibrary`` extra; about two minutes with Debian's ``libopencv-dev`` and
``cmake``) and is never needed otherwise: without it, asking for the method is one clear error.

Each model gives a foreground mask and a background image. The rest of the motion stage works on
them as on OpenCV's subtractors: our shadow test on the model's background
(:func:`~.shadows.shadow_test`, which the models do not have), shadow pixels inside their
region's own foreground given back (:func:`~.shadows.enclosed_shadows`), and the hold
(:class:`~.hold.Hold`) for tracked objects that stop.

BGSLibrary's models print to the process's standard output when they are made and look for a
``./config/<Model>.xml`` of settings (written there when they are destroyed, if the folder exists);
both are kept quiet here, and each model runs with its own defaults.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
from typing import Any, Iterator

import cv2
import numpy as np

from ..errors import ConfigError
from .base import DETECTORS, MotionDetector
from .detectors import binary
from .hold import Hold
from .shadows import enclosed_shadows, shadow_test

__all__ = ["BGSLibrary", "algorithms"]

#: the attributes of ``pybgs`` that are helpers, not models
_NOT_MODELS = frozenset({"read_image", "show_image", "transpose_image"})
_QUIET = threading.Lock()


def _pybgs() -> Any:
    try:
        import pybgs
    except ImportError:
        raise ConfigError("motion.method = bgslibrary needs BGSLibrary's Python binding pybgs, "
                          "which is not installed (pip install pybgs builds it from source with "
                          "OpenCV's development files and cmake)") from None
    return pybgs


def algorithms() -> tuple[str, ...]:
    """The BGSLibrary models installed (empty without ``pybgs``)."""
    try:
        import pybgs
    except ImportError:
        return ()
    return tuple(sorted(n for n in dir(pybgs) if not n.startswith("_") and n not in _NOT_MODELS))


@contextlib.contextmanager
def _native_quiet() -> Iterator[None]:
    """The process's standard output and error sent to /dev/null while BGSLibrary makes or
    destroys a model (its C++ code prints there)."""
    with _QUIET:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        saved = [os.dup(1), os.dup(2)]
        null = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(null, 1)
            os.dup2(null, 2)
            yield
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in (*saved, null):
                os.close(fd)


@DETECTORS.register("bgslibrary")
class BGSLibrary(MotionDetector):
    """BGSLibrary's models (SuBSENSE, PAWCS, ...; needs pybgs) with our shadow test and hold.

    ``algorithm`` names the model by its class name in ``pybgs`` (see the module notes)."""

    wants_color = True
    # SuBSENSE, PAWCS and LOBSTER absorb ghosts by their own feedback; the ghost filter's outline
    # test, tuned on KNN's masks, dropped a third of SuBSENSE's people on the SBI office
    # footage (HumanBody2 recall 0.66 against 0.76 without it: benchmarks/still_people.py)
    own_ghosts = True

    def __init__(self, algorithm: str = "SuBSENSE", shadows: bool = True,
                 shadow_threshold: float = 0.5, hold: bool = True, hold_threshold: int = 30,
                 hold_speed: float = 0.2, accept_s: float = 180.0) -> None:
        pybgs = _pybgs()
        names = algorithms()
        if algorithm not in names:
            raise ConfigError(f"motion.bgslibrary.algorithm must be one of {', '.join(names)}, "
                              f"got {algorithm!r}")
        self.algorithm = algorithm
        self._make = getattr(pybgs, algorithm)
        self.shadows = bool(shadows)
        self.darkest = float(shadow_threshold)
        self.hold = Hold(hold_threshold, accept_s) if hold else None
        # the pipeline passes the boxes and the ghost pixels to a detector that takes them
        self.protect = self.relearns = self.hold is not None
        self.protect_speed = hold_speed if self.hold is not None else None
        self.model = self._new_model()

    def _new_model(self) -> Any:
        with _native_quiet():
            return self._make()

    def set_rate(self, fps: float) -> None:
        if self.hold is not None:
            self.hold.fps = float(fps)

    def apply(self, image: np.ndarray, protect: np.ndarray | None = None,
              relearn: np.ndarray | bool | None = None) -> np.ndarray:
        fg = np.ascontiguousarray(self.model.apply(image))
        if fg.ndim == 3:   # some models give a colour mask
            fg = fg.max(axis=2)
        raw = cv2.compare(fg, 0, cv2.CMP_GT)
        if self.shadows:
            raw = enclosed_shadows(shadow_test(image, self._model_background(), raw,
                                               self.darkest))
        if self.hold is None:
            return binary(raw)
        if relearn is True:
            self.hold.reset()
            relearn = None
        return self.hold.apply(image, raw, protect, relearn if isinstance(relearn, np.ndarray)
                               else None)

    def _model_background(self) -> np.ndarray | None:
        bg = self.model.getBackgroundModel()
        return bg if isinstance(bg, np.ndarray) and bg.size else None

    def relearn(self, image: np.ndarray | None = None) -> None:
        old, self.model = self.model, self._new_model()
        with _native_quiet():
            del old
        if self.hold is not None:
            self.hold.reset()
        if image is not None:
            self.model.apply(image)

    def held(self) -> np.ndarray | None:
        return self.hold.held if self.hold is not None else None

    def background(self) -> np.ndarray | None:
        bg = self._model_background()
        if bg is None:
            return None
        return self.hold.background(bg) if self.hold is not None else bg

    def __del__(self) -> None:
        model = self.__dict__.pop("model", None)
        if model is not None:
            with contextlib.suppress(Exception), _native_quiet():
                del model
