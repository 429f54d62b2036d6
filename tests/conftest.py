"""Fixtures shared by the test modules. Plain helpers live in the ``helpers`` package next to
this file (``from helpers import ann, tracks_of``); pytest puts tests/ on ``sys.path``."""

from __future__ import annotations

import pytest

from helpers.data import require
from helpers.procs import enable_ctrl_c

# the tests that send SIGINT to a motiontrack process need it to start with Ctrl-C enabled,
# also when the suite itself was started in the background of a shell (SIGINT ignored)
enable_ctrl_c()


@pytest.fixture(autouse=True)
def native_logs_as_found():
    """A test running a command with ``--debug`` in this process turns FFmpeg's and OpenCV's own
    messages on in ``os.environ``; the processes later tests start inherit that environment, so
    each test ends with the levels it found."""
    import os

    from motiontrack.io import native_logs

    names = (native_logs.FFMPEG_ENV, native_logs.OPENCV_ENV)
    before = {name: os.environ.get(name) for name in names}
    verbose = native_logs._verbose
    yield
    if native_logs._verbose != verbose or any(os.environ.get(n) != v for n, v in before.items()):
        for name, value in before.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value
        native_logs._verbose = verbose
        native_logs.quiet()


@pytest.fixture
def data():
    """``data("pets09-s2l1", "video.avi")`` → Path (skips or fails when absent)."""
    return require


@pytest.fixture(scope="session")
def scene_runs(tmp_path_factory):
    """``scene_runs(name, seed, *track_options)`` → :class:`helpers.SceneRun`, each run tracked
    once per session and shared by every test that asserts on it."""
    from helpers.runs import SceneRuns

    return SceneRuns(tmp_path_factory.mktemp("scene-runs"))


@pytest.fixture(scope="session")
def pets_camera_run(tmp_path_factory):
    """The folder of ``track video.avi --camera View_001.xml --no-video`` on PETS 2009 S2L1
    frames 1-300 (``tracks.txt`` with world columns, ``summary.json`` with track speeds), run
    once per session for every test asserting on it."""
    video, xml = require("pets09-s2l1", "video.avi"), require("pets09-s2l1", "View_001.xml")
    out = tmp_path_factory.mktemp("pets-camera")
    from motiontrack.cli import main

    assert main(["-q", "track", str(video), "--camera", str(xml), "--no-video", "-o", str(out),
                 "--force"]) == 0
    return out


@pytest.fixture(scope="session")
def dask_session_client():
    """One local Dask cluster of 2 worker processes for the whole session, for the tests of the
    batch and sweep logic (starting a cluster takes seconds). The tests that kill or interrupt
    workers start their own."""
    pytest.importorskip("distributed", reason="dask[distributed] not installed")
    from motiontrack.run.executor import dask_client

    with dask_client(jobs=2) as client:
        yield client


@pytest.fixture
def shared_dask(dask_session_client):
    """The session's Dask client, lent to every local cluster a command opens during the test
    (``motiontrack batch -j N`` runs on it instead of starting one)."""
    from motiontrack.run.executor import reusing_client

    with reusing_client(dask_session_client) as client:
        yield client


@pytest.fixture
def loaded_machine():
    """A busy-loop process on every core for the duration of the test (what must hold when
    the machine is busy: a full test run, other work beside it)."""
    from helpers.procs import cpu_burners

    with cpu_burners() as burners:
        yield burners
