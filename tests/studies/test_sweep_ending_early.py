"""A sweep on a pool of worker processes ending early: stopped by a signal it ends within
seconds, killed it leaves no worker behind, on a full disk it exits 2 with one line; every
finished run is kept."""

from __future__ import annotations

import json
import pickle
import signal
import subprocess
import sys
import time

import pytest

import motiontrack.studies.sweep as sw
from helpers.disk import small_disk
from motiontrack.cli import main
from motiontrack.io.atomic import DiskFullError
from motiontrack.studies.table import read_table

psutil = pytest.importorskip("psutil")

SHORT = "synth:walker?n_frames=8"
#: some 30 s of frames: a run of it is always in progress when the signal comes
LONG = "synth:crossing?n_frames=1500"
#: 2 thresholds x (walker, crossing): r1 walker, r1 crossing, r2 walker, r2 crossing
ARGS = ["-q", "sweep", SHORT, LONG, "--set", "motion.method=median",
        "--param", "motion.median.threshold=0.1,0.2", "--no-figures"]


class Sweep:
    """A ``motiontrack sweep -j 2`` in a process of its own, its output in files (a worker that
    outlives it would hold a pipe open); every process it started is killed at teardown."""

    def __init__(self, tmp_path) -> None:
        self.out = tmp_path / "study"
        self.err_path = tmp_path / "stderr.txt"
        with open(self.err_path, "w") as err:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "motiontrack", *ARGS, "-j", "2", "-o", str(self.out)],
                stdout=subprocess.DEVNULL, stderr=err)
        self.seen: list = []

    def children(self) -> list:
        self.seen = psutil.Process(self.proc.pid).children(recursive=True)
        return self.seen

    def wait_for(self, paths, timeout=90.0) -> None:
        """Wait until every path exists (the runs of the short sequence are finished), noting
        the processes of the sweep meanwhile."""
        end = time.monotonic() + timeout
        while not all(p.exists() for p in paths):
            if self.proc.poll() is not None or time.monotonic() > end:
                pytest.fail(f"the short runs did not finish (exit {self.proc.poll()}): "
                            f"{self.err_path.read_text()}")
            self.children()
            time.sleep(0.05)

    def stderr(self) -> str:
        return self.err_path.read_text()

    def close(self) -> None:
        for p in [*self.seen, psutil.Process(self.proc.pid)] if self.proc.poll() is None \
                else self.seen:
            try:
                p.kill()
            except psutil.NoSuchProcess:
                pass
        self.proc.wait()


@pytest.fixture
def sweep(tmp_path):
    s = Sweep(tmp_path)
    try:
        yield s
    finally:
        s.close()


def _gone(procs, timeout):
    """The processes of ``procs`` still alive (zombies count as gone) after ``timeout`` s."""
    end = time.monotonic() + timeout
    alive = list(procs)
    while alive and time.monotonic() < end:
        alive = [p for p in alive if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
        time.sleep(0.05)
    return alive


def _finished_run(out, run, seq):
    return out / "runs" / f"r{run:03d}" / seq / sw.RUN_RECORD_FILE


@pytest.mark.slow
def test_a_stopped_sweep_ends_within_seconds_and_keeps_its_finished_runs(sweep, monkeypatch):
    out = sweep.out
    sweep.wait_for([_finished_run(out, 1, "walker"), _finished_run(out, 2, "walker")])
    sweep.children()
    t0 = time.monotonic()
    sweep.proc.send_signal(signal.SIGINT)  # both crossing runs are in progress
    try:
        sweep.proc.wait(timeout=8)
    except subprocess.TimeoutExpired:
        pytest.fail("the sweep went on with its runs after SIGINT")
    assert time.monotonic() - t0 < 8
    err = sweep.stderr()
    assert sweep.proc.returncode == 130, err
    assert "2 of 4 runs finished" in err
    assert json.loads((out / "summary.json").read_text()) == {
        "status": "interrupted", "interrupted": True, "runs_done": 2, "runs": 4}
    assert [(r["run"], r["sequence"]) for r in read_table(out / "results.csv")] == [
        (1, "walker"), (2, "walker")]
    assert not _finished_run(out, 1, "crossing").exists()
    assert _gone(sweep.seen, timeout=2) == []   # and its workers have ended

    # --resume runs the two stopped runs only (recorded here instead of run)
    calls = []
    row = json.loads(_finished_run(out, 1, "walker").read_text())["row"]

    def record(spec, should_stop=None):
        calls.append((spec.run, spec.sequence.name))
        files = {f"{spec.run_dir()}/{n}.txt": "" for n in ("tracks", "regions")}
        return {"row": {**row, "run": spec.run, "sequence": spec.sequence.name}, "files": files}

    monkeypatch.setattr(sw, "execute_run", record)
    assert main([*ARGS, "--resume", "-o", str(out)]) == 0
    assert calls == [(1, "crossing"), (2, "crossing")]
    assert [r["sequence"] for r in read_table(out / "results.csv")] == [
        "walker", "crossing", "walker", "crossing"]


@pytest.mark.slow
def test_the_workers_of_a_killed_sweep_die_with_it(sweep):
    sweep.wait_for([_finished_run(sweep.out, 1, "walker")])
    children = sweep.children()
    assert len(children) >= 2              # the two workers (and multiprocessing's tracker)
    sweep.proc.kill()                      # SIGKILL: the sweep cannot stop its pool itself
    sweep.proc.wait()
    assert _gone(children, timeout=5) == []


def test_a_full_disk_in_a_worker_reaches_the_parent_as_itself():
    exc = pickle.loads(pickle.dumps(DiskFullError("/o/runs/r001/a/motion.webm", "No space left")))
    assert isinstance(exc, DiskFullError)
    assert str(exc) == "disk full writing /o/runs/r001/a/motion.webm: No space left"
    assert exc.reason == "No space left" and exc.path.name == "motion.webm"


@pytest.mark.slow
def test_a_pool_sweep_meeting_a_full_disk_exits_2_with_one_line(tmp_path, capfd):
    # each run's annotated video takes about 0.75 MB of the 2 MB, and a video leaves 1 MiB free
    with small_disk(tmp_path / "disk") as disk:
        out = disk / "study"
        code = main(["-q", "sweep", "synth:walker?n_frames=40", "--set", "motion.method=median",
                     "--param", "motion.median.threshold=0.1,0.2,0.3,0.4", "--save", "annotated",
                     "--no-figures", "-j", "2", "-o", str(out)])
        err = capfd.readouterr().err.strip().splitlines()   # the workers' stderr too
        assert code == 2
        assert len(err) == 1 and err[0].startswith("motiontrack: error: disk full writing"), err
        assert "annotated.webm" in err[0]
        summary = json.loads((out / "summary.json").read_text())
        assert summary["status"].startswith("disk full writing") and summary["runs_done"] < 4
        rows = read_table(out / "results.csv") if summary["runs_done"] else []
        assert len(rows) == summary["runs_done"]
        assert all(_finished_run(out, r["run"], "walker").is_file() for r in rows)


def test_a_serial_sweep_stops_its_run_after_the_current_frame(tmp_path):
    from motiontrack.config import load_config
    from motiontrack.studies.sweep import run_sweep, study_from_args

    study = study_from_args(["synth:walker?n_frames=40"], None,
                            ["motion.median.threshold=0.1,0.2,0.3"],
                            load_config(None, ["motion.method=median"]))
    out = tmp_path / "study"
    polls = []

    def stop_in_second_run():
        polls.append(_finished_run(out, 1, "walker").exists())
        return polls.count(True) >= 5       # the fifth frame of run 2

    with pytest.raises(KeyboardInterrupt):
        run_sweep(study, out, figures=False, should_stop=stop_in_second_run)
    assert json.loads((out / "summary.json").read_text())["runs_done"] == 1
    assert polls.count(True) == 5           # run 2 ended at that frame; run 3 never started
    assert not (out / "runs" / "r002").exists()
