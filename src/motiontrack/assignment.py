"""``linear_sum_assignment``: SciPy's assignment solver (the one TrackEval uses), loaded without
importing the ``scipy.optimize`` package.

Importing ``scipy.optimize`` costs about a second of CPU (it pulls in ``scipy.linalg``,
``scipy.special``, ``scipy.fft``, ...), four times numpy's own import, and the tracking metrics
need only its compiled solver, the extension module ``scipy/optimize/_lsap``, which depends on
numpy alone. Loading that file directly keeps ``motiontrack evaluate`` quick to start. It is the
very function ``scipy.optimize.linear_sum_assignment`` is (same code, same tie-breaking), so
results do not change. Where this SciPy keeps no such file, or ``scipy.optimize`` is already
imported, the package's function is used.
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import os
import sys
from typing import Callable

__all__ = ["linear_sum_assignment"]


def _load() -> Callable:
    if "scipy.optimize" not in sys.modules:
        try:
            spec = importlib.util.find_spec("scipy")
            folder = os.path.join(os.path.dirname(spec.origin), "optimize")
            for suffix in importlib.machinery.EXTENSION_SUFFIXES:
                path = os.path.join(folder, "_lsap" + suffix)
                if os.path.isfile(path):
                    loader = importlib.machinery.ExtensionFileLoader("scipy.optimize._lsap", path)
                    mod = importlib.util.module_from_spec(
                        importlib.util.spec_from_loader("scipy.optimize._lsap", loader))
                    loader.exec_module(mod)
                    return mod.linear_sum_assignment
        except (ImportError, AttributeError, OSError, TypeError):
            pass  # another SciPy layout: the ordinary import below
    from scipy.optimize import linear_sum_assignment as lsa

    return lsa


linear_sum_assignment = _load()
