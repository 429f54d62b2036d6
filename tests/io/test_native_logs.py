"""FFmpeg's and OpenCV's own stderr lines: an unreadable or damaged video gives motiontrack's one
line alone; ``--debug`` shows theirs too. Each command runs in a process of its own: FFmpeg
reads its log level when the process first opens a video."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from helpers import require


def _track(*args, cwd):
    proc = subprocess.run([sys.executable, "-m", "motiontrack", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=120)
    return proc.returncode, proc.stderr.splitlines(), proc.stdout.splitlines()


@pytest.fixture
def random_mp4(tmp_path):
    path = tmp_path / "corrupt.mp4"
    path.write_bytes(np.random.default_rng(7).integers(0, 256, 100_000, np.uint8).tobytes())
    return path


def test_a_file_of_random_bytes_gives_our_one_line_alone(random_mp4, tmp_path):
    code, err, _ = _track("track", str(random_mp4), "-o", "out", cwd=tmp_path)
    assert code == 3
    assert len(err) == 1 and err[0].startswith("motiontrack: error: cannot open"), err
    assert "corrupt.mp4" in err[0]


def test_debug_shows_what_ffmpeg_says_about_the_file(random_mp4, tmp_path):
    code, err, out = _track("--debug", "track", str(random_mp4), "-o", "out", cwd=tmp_path)
    assert code == 3
    # OpenCV passes FFmpeg's lines on through its own logger, which writes to stdout
    assert any("moov atom not found" in line for line in err + out), (err, out)


@pytest.mark.slow
def test_a_truncated_video_gives_our_one_warning_alone(tmp_path):
    video = tmp_path / "cut.avi"       # the first 16 frames and part of the 17th
    video.write_bytes(require("pets09-s2l1", "video.avi").read_bytes()[:300_000])
    code, err, _ = _track("-q", "track", str(video), "-o", "out", "--codec", "mjpg", cwd=tmp_path)
    assert code == 0
    assert len(err) == 1 and "decoding stopped at frame" in err[0], err
