"""The run layer: one job loop, its outputs on success, interruption and failure, and the
Python iterator's threads."""

from __future__ import annotations

import json
import subprocess
import sys
import threading

import numpy as np
import pytest

import motiontrack
from motiontrack.cli import main
from motiontrack.config import load_config
from motiontrack.errors import InputError
from motiontrack.io.sources import SCHEMES, ArraySource, open_source
from motiontrack.io.video import VideoSink
from motiontrack.pipeline import open_configured_source
from motiontrack.run import Job, track_job
from motiontrack.run.processors import TrackProcessor
from motiontrack.run.writers import TracksWriter, VideoWriter

from helpers.writers import FailAt

WALKER = "synth:walker?n_frames=12"


def _files(folder):
    return sorted(p.name for p in folder.iterdir()) if folder.exists() else []


def _job(out, *extra, force=False):
    cfg = load_config(None, ['output.codec="mjpg"'])
    src = open_configured_source(WALKER, cfg.source)
    writers = [TracksWriter(out), VideoWriter("video", out / "annotated.avi", "mjpg"), *extra]
    return Job(src, TrackProcessor(cfg, src.info), writers, out, force=force,
               config=(lambda c, p: p.write_text("cfg\n"), cfg))


def test_a_failed_run_removes_its_outputs_so_the_retry_needs_no_force(tmp_path):
    out = tmp_path / "o"
    with pytest.raises(RuntimeError, match="encoder gave up"):
        _job(out, FailAt(5)).run()
    assert _files(out) == []                      # no tracks, video, config, summary or .part
    summary = _job(out).run()                     # the same folder, without --force
    assert summary.frames == 12 and summary.status == "complete"
    assert _files(out) == ["annotated.avi", "config.toml", "summary.json", "tracks.txt"]


def test_an_unencodable_codec_leaves_no_config_behind(tmp_path, monkeypatch, capsys):
    def refuse(self, w, h):
        raise InputError(f"this OpenCV build cannot encode {self.codec} video to {self.path}")

    out = tmp_path / "o"
    argv = ["track", WALKER, "-o", str(out), "--codec", "mjpg"]
    with monkeypatch.context() as m:
        m.setattr(VideoSink, "_open", refuse)
        assert main(argv) == 2
    assert "cannot encode" in capsys.readouterr().err
    assert _files(out) == []
    assert main(argv) == 0                        # the retry is not blocked by "output exists"
    assert "config.toml" in _files(out)


def test_a_stop_request_keeps_every_finished_frame(tmp_path):
    out = tmp_path / "o"
    job = _job(out)
    seen = []

    def stop() -> bool:
        seen.append(1)
        return len(seen) == 4                     # after the fourth complete frame

    with pytest.raises(KeyboardInterrupt):
        job.run(should_stop=stop)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 4 and summary["interrupted"] and summary["status"] == "interrupted"
    assert (out / "annotated.avi").is_file() and (out / "config.toml").is_file()
    assert not [n for n in _files(out) if n.endswith(".part") or n.startswith(".")]


def test_every_output_is_refused_when_it_exists_unless_forced(tmp_path):
    out = tmp_path / "o"
    _job(out).run()
    with pytest.raises(InputError, match="output exists"):
        _job(out)
    assert _job(out, force=True).run().frames == 12


def test_the_track_job_writes_what_the_pipeline_yields(tmp_path):
    cfg = load_config(None, ["output.video=false"])
    spec = "synth:walker?n_frames=40"
    summary = track_job(spec, cfg, tmp_path / "o").run()
    rows = np.loadtxt(tmp_path / "o" / "tracks.txt", delimiter=",", ndmin=2)
    with motiontrack.track(spec, cfg) as frames:
        expected = [(r.index + 1, t.id) for r in frames for t in r.tracks]
    assert [(int(f), int(i)) for f, i in rows[:, :2]] == expected
    assert summary.tracks == len({i for _, i in expected}) == 1
    assert summary.accuracy is not None            # the synthetic scene brings its ground truth


def _decode_threads() -> int:
    return sum(t.name.startswith("motiontrack") for t in threading.enumerate())


def test_a_track_iterator_stops_its_threads_when_closed():
    before = _decode_threads()
    with motiontrack.track(WALKER) as frames:
        first = next(frames)
    assert first.index == 0
    assert _decode_threads() == before
    frames.close()                                 # closing twice is harmless


@pytest.mark.parametrize("how", ["script", "-c"])
def test_a_track_iterator_left_open_at_interpreter_exit_ends_the_process_cleanly(tmp_path, how):
    # the decoding and detection threads must not outlive the interpreter (C++ abort, exit 134)
    code = "import motiontrack\nit = motiontrack.track('synth:walker')\nnext(it)\n"
    script = tmp_path / "left_open.py"
    script.write_text(code)
    argv = [str(script)] if how == "script" else ["-c", code]
    proc = subprocess.run([sys.executable, *argv], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""


def test_sources_named_by_a_scheme_come_from_the_registry():
    assert type(open_source("synth:walker")).__name__ == "SyntheticSource"
    frames = [np.zeros((4, 6, 3), np.uint8)] * 3

    @SCHEMES.register("test-blank", "three blank frames")
    def blank(spec, start, max_frames):
        return ArraySource(frames, name=spec, start=start, max_frames=max_frames)

    src = open_source("test-blank:x", start=1)
    assert src.info.name == "test-blank:x" and len(list(src)) == 2
    assert "test-blank" in SCHEMES.names()


def test_a_source_far_beyond_the_defaults_is_opened_with_a_memory_warning(tmp_path, caplog):
    import cv2

    from motiontrack.config import SourceConfig

    cv2.imwrite(str(tmp_path / "f1.png"), np.zeros((2200, 4000, 3), np.uint8))   # 8.8 Mpx > 4K
    with caplog.at_level("WARNING", logger="motiontrack"):
        src = open_configured_source(str(tmp_path), SourceConfig())
    src.close()
    assert any("4000x2200" in r.getMessage() and "GB of memory" in r.getMessage()
               for r in caplog.records)
