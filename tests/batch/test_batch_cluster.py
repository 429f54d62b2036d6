"""motiontrack batch against a scheduler and workers started as separate processes."""

from __future__ import annotations

import csv
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("distributed")

from helpers import communicate_or_dump, free_port  # noqa: E402
from motiontrack.cli import main  # noqa: E402
from motiontrack.config import PipelineConfig, apply_overrides  # noqa: E402
from motiontrack.run.jobs import track_job  # noqa: E402

SCENES = ["synth:walker?n_frames=30", "synth:crossing?n_frames=30"]
DASK = Path(sys.executable).with_name("dask")


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=10)


@pytest.fixture()
def scheduler_address(tmp_path):
    """A ``dask scheduler`` and a ``dask worker --nworkers 2`` process on free local ports,
    yielded once the scheduler sees both workers."""
    if not DASK.exists():
        pytest.skip("the dask command is not installed beside this Python")
    from distributed import Client

    port = free_port()
    addr = f"tcp://127.0.0.1:{port}"
    logs = [open(tmp_path / n, "wb") for n in ("scheduler.log", "worker.log")]
    procs = [subprocess.Popen([str(DASK), "scheduler", "--host", "127.0.0.1", "--port", str(port),
                               "--dashboard-address", f"127.0.0.1:{free_port()}"],
                              stdout=logs[0], stderr=subprocess.STDOUT)]
    try:
        procs.append(subprocess.Popen([str(DASK), "worker", addr, "--nworkers", "2",
                                       "--nthreads", "1", "--host", "127.0.0.1",
                                       "--no-dashboard"],
                                      stdout=logs[1], stderr=subprocess.STDOUT))
        deadline = time.monotonic() + 90
        with Client(addr, timeout=60) as cl:
            while len(cl.scheduler_info()["workers"]) < 2:
                if time.monotonic() > deadline or any(p.poll() is not None for p in procs):
                    raise RuntimeError("the Dask cluster did not start: "
                                       + (tmp_path / "worker.log").read_text(errors="replace"))
                time.sleep(0.2)
        yield addr
    finally:
        for p in reversed(procs):
            _stop(p)
        for f in logs:
            f.close()


@pytest.mark.slow
def test_batch_on_an_external_scheduler_matches_track_alone(tmp_path, scheduler_address):
    results = tmp_path / "results"
    code = main(["batch", *SCENES, "-o", str(results), "--cluster", scheduler_address,
                 "--set", "output.video=false"])
    assert code == 0
    with open(results / "index.csv", newline="", encoding="utf-8") as fh:
        index = {r["name"]: r for r in csv.DictReader(fh)}
    assert [index[n]["status"] for n in ("synth-walker", "synth-crossing")] == ["done", "done"]
    assert all(index[n]["worker"] not in ("", "local") for n in index)
    cfg = apply_overrides(PipelineConfig(), ["output.video=false"])
    for src, name in zip(SCENES, ("synth-walker", "synth-crossing")):
        alone = tmp_path / f"alone-{name}"
        track_job(src, cfg, alone).run()
        assert (results / name / "tracks.txt").read_bytes() == (alone / "tracks.txt").read_bytes()


@pytest.mark.slow
def test_an_interrupted_batch_frees_the_clusters_workers_within_seconds(tmp_path,
                                                                         scheduler_address,
                                                                         loaded_machine):
    """Ctrl-C reaches only the client's process on a cluster of its own; Dask cannot stop a
    running task, so the videos running stop themselves on the batch's stop event. Every
    core is busy meanwhile."""
    import os
    import signal

    from distributed import Client

    results = tmp_path / "results"
    long = ["synth:walker?n_frames=3000", "synth:crossing?n_frames=3000"]
    proc = subprocess.Popen([sys.executable, "-m", "motiontrack", "batch", *long, "-o",
                             str(results), "--cluster", scheduler_address, "--set",
                             "output.video=false"], stdout=subprocess.PIPE,
                            env={**os.environ, "PYTHONFAULTHANDLER": "1"},
                            stderr=subprocess.PIPE, text=True)
    try:
        with Client(scheduler_address, timeout=30) as cl:
            deadline = time.monotonic() + 120
            while sum(len(v) for v in cl.processing().values()) < 2:
                assert time.monotonic() < deadline and proc.poll() is None
                time.sleep(0.2)
            time.sleep(2.0)   # both videos are tracking frames
            os.kill(proc.pid, signal.SIGINT)
            _, err = communicate_or_dump(proc, 60)
            assert proc.returncode == 130, err
            t0 = time.monotonic()
            while any(cl.call_stack().values()):   # a task still executing on a worker
                assert time.monotonic() - t0 < 15, cl.call_stack()
                time.sleep(0.2)
    finally:
        if proc.poll() is None:
            proc.kill()
    with open(results / "index.csv", newline="", encoding="utf-8") as fh:
        assert [r["status"] for r in csv.DictReader(fh)] == ["interrupted", "interrupted"]
    time.sleep(1.0)   # the workers' runs remove their own partial folders as they stop
    assert not list(results.glob(".*.partial")) and not (results / "synth-walker").exists()
