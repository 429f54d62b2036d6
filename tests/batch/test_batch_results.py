"""What a batch's results folder says is what it holds: names that are not the batch's own
files, truncated videos marked so, ``--resume`` keeping only the runs it committed, an index
never older than its CSV. Videos run in this process (:func:`run_video`), no cluster."""

from __future__ import annotations

import json
import logging
import shutil
from pathlib import Path

import pytest

from motiontrack.batch import runner
from motiontrack.batch.combined import combined_metrics
from motiontrack.batch.runner import (BatchTask, _Frames, _resumed_rows, read_index, run_video,
                                      write_index)
from motiontrack.batch.sources import Video
from motiontrack.cli import main
from motiontrack.config import PipelineConfig, apply_overrides, to_dict
from motiontrack.io.atomic import DiskFullError
from motiontrack.run.folder import RunFolder

WALKER = "synth:walker?n_frames=3"
CROSSING = "synth:crossing?n_frames=3"


@pytest.fixture(autouse=True)
def _package_logging():
    """``main`` gives the package's logger a handler on the standard error of the test that
    called it and stops its records there: each test starts without it, so that its records
    reach ``caplog`` and no closed stream."""
    logger = logging.getLogger("motiontrack")
    handlers, level, propagate = logger.handlers[:], logger.level, logger.propagate
    logger.handlers[:] = []
    logger.setLevel(logging.NOTSET)
    logger.propagate = True
    yield
    logger.handlers[:] = handlers
    logger.setLevel(level)
    logger.propagate = propagate


def _task(results: Path, name: str, source: str) -> BatchTask:
    cfg = apply_overrides(PipelineConfig(), ["output.video=false"])
    return BatchTask(Video(name, source), str(results), to_dict(cfg), "c0ffee")


def _done(results: Path, *videos: tuple[str, str]) -> list[Video]:
    """Run each ``(name, source)`` into ``results`` as a batch does and write the index."""
    rows = [run_video(_task(results, n, s)) for n, s in videos]
    assert [r["status"] for r in rows] == ["done"] * len(rows)
    write_index(rows, results / "index.csv")
    return [Video(n, s) for n, s in videos]


# --------------------------------------------------------------------------- names
@pytest.mark.parametrize("stem", ["index.csv", "index.parquet", "combined.json", "counts.csv",
                                  "totals.json", "events.db", "Index.CSV"])
def test_a_video_named_as_a_batch_file_is_refused_before_any_video_runs(tmp_path, capsys, stem):
    results = tmp_path / "results"
    code = main(["batch", str(tmp_path / f"{stem}.avi"), WALKER, "-o", str(results)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and f"video name '{stem}' is the name of a file the batch writes" in err[0]
    assert not results.exists()


# ----------------------------------------------------------------------- truncated
def test_a_truncated_video_is_a_truncated_row_not_a_done_one(tmp_path):
    from helpers.video_files import write_synth_video

    video = tmp_path / "walk.avi"
    write_synth_video(video, "synth:walker?n_frames=12")
    data = video.read_bytes()
    video.write_bytes(data[:len(data) // 2])
    results = tmp_path / "results"
    row = run_video(_task(results, "walk", str(video)))
    assert row["status"] == "truncated"
    assert 0 < row["frames"] < 12 and "ended early" in row["error"]
    assert RunFolder(results / "walk").summary()["truncated"] is True
    write_index([row], results / "index.csv")
    assert read_index(results / "index.csv")["walk"]["status"] == "truncated"
    # a truncated run is not kept by --resume: the file may be whole by then
    assert _resumed_rows(results, [Video("walk", str(video))], "c0ffee") == {}


# -------------------------------------------------------------------------- resume
def test_resume_keeps_only_the_videos_whose_outputs_are_as_committed(tmp_path, caplog):
    results = tmp_path / "results"
    videos = _done(results, ("a", WALKER), ("b", CROSSING), ("c", WALKER), ("d", WALKER),
                   ("e", WALKER))
    summary = json.loads((results / "a" / "summary.json").read_text())
    files = summary["batch"]["files"]
    assert set(files) == {"tracks.txt", "gt.txt", "config.toml"}
    tracks = results / "a" / "tracks.txt"
    assert files["tracks.txt"]["bytes"] == tracks.stat().st_size
    assert len(files["tracks.txt"]["sha256"]) == 64

    # three frames confirm no track (tracks.txt is empty): config.toml stands for any output
    (results / "b" / "tracks.txt").unlink()                               # deleted
    cut = results / "c" / "config.toml"
    cut.write_bytes(cut.read_bytes()[:-20])                                # truncated
    edited = results / "d" / "config.toml"
    text = edited.read_text()
    edited.write_text(text.replace("true", "fals", 1))                     # a value tampered
    assert len(edited.read_text()) == len(text) and edited.read_text() != text
    with caplog.at_level(logging.WARNING, logger="motiontrack.batch.runner"):
        kept = _resumed_rows(results, videos, "c0ffee")
    assert list(kept) == ["a", "e"]
    assert "b: tracks.txt is missing" in caplog.text
    assert "c: config.toml changed" in caplog.text and "d: config.toml changed" in caplog.text


def test_resume_runs_again_a_folder_holding_another_sources_run(tmp_path, caplog):
    results = tmp_path / "results"
    _done(results, ("a", WALKER), ("b", CROSSING))
    (results / "a").rename(results / "x")
    (results / "b").rename(results / "a")
    (results / "x").rename(results / "b")
    with caplog.at_level(logging.WARNING, logger="motiontrack.batch.runner"):
        kept = _resumed_rows(results, [Video("a", WALKER), Video("b", CROSSING)], "c0ffee")
    assert kept == {}
    assert f"holds the run of {CROSSING}, not of {WALKER}" in caplog.text


def test_a_resumed_row_that_disagrees_with_its_folder_is_made_from_the_summary(tmp_path):
    results = tmp_path / "results"
    videos = _done(results, ("a", WALKER))
    index = results / "index.csv"
    index.write_text(index.read_text().replace(WALKER, "synth:other"))     # edited by hand
    kept = _resumed_rows(results, videos, "c0ffee")
    summary = RunFolder(results / "a").summary()
    assert kept["a"]["source"] == WALKER and kept["a"]["frames"] == summary["frames"] == 3


def test_a_summary_nested_100000_deep_is_a_warning_and_the_video_runs_again(tmp_path, caplog,
                                                                             capsys):
    results = tmp_path / "results"
    videos = _done(results, ("a", WALKER))
    (results / "a" / "summary.json").write_text("[" * 100_000 + "]" * 100_000)
    with caplog.at_level(logging.WARNING, logger="motiontrack.batch.runner"):
        assert _resumed_rows(results, videos, "c0ffee") == {}
    assert "summary.json: nested too deeply; the video runs again" in caplog.text
    # the other readers of summary.json: analyze's frame rate from the run beside the tracks
    assert RunFolder(results / "a").frame_rate() is None
    scene = tmp_path / "scene.toml"
    scene.write_text('[[line]]\nname = "g"\npoints = [[0, 10], [20, 10]]\n')
    code = main(["analyze", str(results / "a" / "tracks.txt"), "--scene", str(scene), "-o",
                 str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "give --fps" in err[0]


# --------------------------------------------------------------------------- index
def test_a_parquet_index_that_cannot_be_written_is_removed_not_left_stale(tmp_path, monkeypatch,
                                                                         caplog):
    pytest.importorskip("pyarrow")
    index = tmp_path / "index.csv"
    write_index([{"name": "a", "status": "done"}], index)
    assert index.with_suffix(".parquet").is_file()

    def full(path, data):
        raise DiskFullError(path, "No space left on device")

    monkeypatch.setattr(runner, "atomic_write_bytes", full)
    with caplog.at_level(logging.WARNING, logger="motiontrack.batch.runner"):
        write_index([{"name": "a", "status": "done"}, {"name": "b", "status": "failed"}], index)
    assert list(read_index(index)) == ["a", "b"]
    assert not index.with_suffix(".parquet").exists()
    assert "index.parquet not written (disk full writing" in caplog.text
    assert "removed, index.csv holds the index" in caplog.text


# ------------------------------------------------------------------------- stopping
def test_a_video_the_batch_stops_while_its_folder_goes_is_interrupted_not_failed(
        tmp_path, monkeypatch, caplog):
    """The client removes the partial folder of a video not done while its run commits (a
    batch stopped by SIGTERM): the run's error is the stop's, not a FileNotFoundError."""
    results = tmp_path / "results"

    class Stopped(_Frames):
        def should_stop(self) -> bool:
            self.stopped = True
            shutil.rmtree(results / ".a.partial", ignore_errors=True)
            return True

    monkeypatch.setattr(runner, "_Frames", Stopped)
    with caplog.at_level(logging.WARNING):
        row = run_video(_task(results, "a", WALKER))
    assert row["status"] == "interrupted", row
    assert "FileNotFoundError" not in caplog.text and "FileNotFoundError" not in row["error"]
    assert not (results / ".a.partial").exists() and not (results / "a").exists()


def test_combined_metrics_count_truncated_videos_over_the_frames_they_hold(tmp_path):
    results = tmp_path / "results"
    _done(results, ("a", WALKER))
    rows = [{"name": "a", "status": "truncated"}]
    assert combined_metrics(results, rows)["sequences"] == ["a"]


def test_a_video_whose_folder_goes_before_its_run_sees_the_stop_is_interrupted(tmp_path,
                                                                              monkeypatch):
    """The stop event is polled once a second: the folder may go before the run sees it."""
    results = tmp_path / "results"

    class SeenLate(_Frames):
        def should_stop(self) -> bool:
            shutil.rmtree(results / ".a.partial", ignore_errors=True)
            self.stopped = self.stopped or self.next_check == 0.0   # set, seen when checked now
            return self.stopped

    monkeypatch.setattr(runner, "_Frames", SeenLate)
    row = run_video(_task(results, "a", WALKER))
    assert row["status"] == "interrupted", row
    assert not (results / ".a.partial").exists() and not (results / "a").exists()
