"""Event clips: Motion-JPEG AVI files written from JPEGs and read back as the same JPEGs."""

from __future__ import annotations

import cv2
import numpy as np

from motiontrack.io.clips import clip_jpegs, read_clip, write_mjpeg_clip


def test_a_clip_gives_back_the_jpegs_it_was_written_with(tmp_path):
    jpegs = [cv2.imencode(".jpg", np.full((24, 32, 3), 10 * k, np.uint8))[1].tobytes()
             for k in range(5)]
    path = write_mjpeg_clip(tmp_path / "clip.avi", jpegs, 12.5)
    assert clip_jpegs(path) == (jpegs, 12.5)              # muxed and demuxed, never re-encoded
    frames, fps = read_clip(path)
    assert fps == 12.5 and [round(f.mean()) for f in frames] == [0, 10, 20, 30, 40]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["clip.avi"]   # no temporary file
