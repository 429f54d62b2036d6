"""Event clips: Motion-JPEG AVI files written from JPEGs and read back as the same JPEGs."""

from __future__ import annotations

import cv2
import numpy as np

from motiontrack.io.clips import ClipWriter, clip_jpegs, read_clip, write_mjpeg_clip


def test_a_clip_gives_back_the_jpegs_it_was_written_with(tmp_path):
    jpegs = [cv2.imencode(".jpg", np.full((24, 32, 3), 10 * k, np.uint8))[1].tobytes()
             for k in range(5)]
    path = write_mjpeg_clip(tmp_path / "clip.avi", jpegs, 12.5)
    assert clip_jpegs(path) == (jpegs, 12.5)              # muxed and demuxed, never re-encoded
    frames, fps = read_clip(path)
    assert fps == 12.5 and [round(f.mean()) for f in frames] == [0, 10, 20, 30, 40]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["clip.avi"]   # no temporary file


def test_a_clip_being_written_is_on_disk_under_a_temporary_name_until_it_ends(tmp_path):
    rng = np.random.default_rng(0)
    jpegs = [cv2.imencode(".jpg", rng.integers(0, 255, (120, 160, 3), np.uint8))[1].tobytes()
             for _ in range(40)]                     # noise: every picture tens of kB
    writer = ClipWriter(tmp_path / "clip.avi", 5.0)
    for jpeg in jpegs:
        writer.add(jpeg)
    (part,) = tmp_path.iterdir()
    assert part.name.endswith(".part.avi") and not (tmp_path / "clip.avi").exists()
    assert part.stat().st_size >= 0.8 * sum(map(len, jpegs))   # written, not held
    assert writer.close() == tmp_path / "clip.avi"
    assert [p.name for p in tmp_path.iterdir()] == ["clip.avi"]
    assert clip_jpegs(tmp_path / "clip.avi") == (jpegs, 5.0)


def test_an_aborted_clip_leaves_nothing(tmp_path):
    writer = ClipWriter(tmp_path / "clip.avi", 5.0)
    writer.add(cv2.imencode(".jpg", np.zeros((24, 32, 3), np.uint8))[1].tobytes())
    writer.abort()
    assert list(tmp_path.iterdir()) == []
