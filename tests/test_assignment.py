"""The assignment solver: SciPy's own function, loaded without importing scipy.optimize."""

from __future__ import annotations

import subprocess
import sys

import numpy as np


def test_assignment_solver_is_scipys_without_importing_scipy_optimize():
    code = ("import sys; from motiontrack.assignment import linear_sum_assignment as f; "
            "print(sorted(m for m in sys.modules if m.startswith('scipy')), f.__name__)")
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                         text=True).stdout.split()
    assert out == ["['scipy.optimize._lsap']", "linear_sum_assignment"]
    from scipy.optimize import linear_sum_assignment as scipy_lsa

    from motiontrack.assignment import linear_sum_assignment

    rng = np.random.default_rng(3)
    for _ in range(300):  # small integer costs: many ties, so tie-breaking is compared too
        m = rng.integers(0, 3, (rng.integers(0, 7), rng.integers(0, 7))).astype(float)
        for maximize in (False, True):
            a = linear_sum_assignment(m, maximize=maximize)
            b = scipy_lsa(m, maximize=maximize)
            assert [x.tolist() for x in a] == [x.tolist() for x in b]


def test_the_track_command_loads_no_scipy_package_beyond_the_solver():
    """Importing scipy.optimize or scipy.ndimage costs a third to half a second of every
    command's start; the pipeline needs neither."""
    code = ("import sys, motiontrack.run.jobs, motiontrack.cli.track; "
            "print(sorted(m for m in sys.modules if m.startswith('scipy')))")
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                         text=True).stdout.strip()
    assert out == "['scipy.optimize._lsap']"
