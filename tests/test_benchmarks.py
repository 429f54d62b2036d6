"""The benchmark scripts run (their speed targets are printed by the scripts, never asserted
here): each is run on a few frames and its output checked for what it must report."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from conftest import REPO, data_root


@pytest.mark.slow
def test_stages_benchmark_reports_every_stage(data):
    data("pets09-s2l1", "video.avi")
    out = subprocess.run([sys.executable, str(REPO / "benchmarks" / "stages.py"), "--data",
                          str(data_root()), "--frames", "20", "--repeat", "1"],
                         capture_output=True, text=True, timeout=120, check=True).stdout
    times = dict(re.findall(r"^(\S.*?)\s{2,}(\d+\.\d+)", out, re.M))
    stages = ["decode", "preprocess", "motion detector", "mask clean-up", "ghosts + regions",
              "head splitting", "tracker"]
    assert all(s in times for s in stages), out
    assert all(float(times[s]) > 0 for s in ("decode", "preprocess", "motion detector")), out
    # the total is the sum of the stages after decoding
    assert abs(float(times["all stages"]) - sum(float(times[s]) for s in stages[1:])) < 0.02, out


@pytest.mark.slow
def test_detections_benchmark_reports_every_row(data):
    data("pets09-s2l1", "video.avi")
    out = subprocess.run([sys.executable, str(REPO / "benchmarks" / "detections.py"), "--data",
                          str(data_root()), "--frames", "40", "--seeds", "1"],
                         capture_output=True, text=True, timeout=120, check=True).stdout
    rows = re.findall(r"^\s*(\d\.\d\d)\s+(\d\.\d\d)\s+(\d\.\d\d)\s+(\d\.\d)((?:\s+-?\d+\.\d+){6})$",
                      out, re.M)
    assert len(rows) == 8, out
    perfect = [float(v) for v in rows[0][4].split()]
    # perfect detections: every reported box is a person
    assert rows[0][:4] == ("0.00", "0.00", "0.00", "0.0") and perfect[4] == 1.0, out
