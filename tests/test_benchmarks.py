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


@pytest.mark.slow
def test_serve_benchmark_with_browsers_reports_each_browser_count():
    import importlib.util
    import os
    import shutil

    if not (shutil.which("chromium") and (shutil.which("chromedriver")
                                          or os.access("/usr/bin/chromedriver", os.X_OK))
            and importlib.util.find_spec("selenium") and importlib.util.find_spec("uvicorn")):
        if os.environ.get("MOTIONTRACK_REQUIRE_DATA") == "1":
            pytest.fail("chromium, chromedriver, selenium or uvicorn missing and "
                        "MOTIONTRACK_REQUIRE_DATA=1")
        pytest.skip("chromium, chromedriver, selenium or uvicorn missing")
    out = subprocess.run([sys.executable, str(REPO / "benchmarks" / "serve.py"), "--browsers",
                          "--seconds", "1", "--rounds", "1", "--viewers", "0,1"],
                         capture_output=True, text=True, timeout=240, check=True).stdout
    rows = {int(n): [float(v) for v in rest.split()] for n, rest in
            re.findall(r"^\s+(\d+)((?:\s+\d+\.\d+){4})$", out, re.M)}
    assert sorted(rows) == [0, 1], out
    fps, ratio, _, browsers_cpu = rows[0]
    assert fps > 0 and ratio == 1.0, out
    # a browser showing the page decodes its MJPEG picture: its processes use CPU
    assert rows[1][0] > 0 and rows[1][3] > browsers_cpu, out
    assert "frame -> picture" not in out, out    # the latency run is the socket mode's
