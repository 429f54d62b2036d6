"""Video sinks: WebM through PyAV (fast real-time libvpx) or OpenCV, atomic files, odd sizes."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiontrack.errors import InputError
from motiontrack.io.video import VideoSink

# PyAV is a dev dependency (the ``video`` extra), so its tests run, never skip, under ``make test``


def _frames(n: int, w: int, h: int) -> list[np.ndarray]:
    """A bright square moving on a textured background (so the encoder has something to do)."""
    rng = np.random.default_rng(0)
    bg = cv2.GaussianBlur(rng.integers(0, 255, (h, w, 3), dtype=np.uint8), (7, 7), 0)
    out = []
    for k in range(n):
        img = bg.copy()
        cv2.rectangle(img, (5 + 3 * k, 10), (25 + 3 * k, 40), (40, 220, 250), -1)
        out.append(img)
    return out


def _read(path) -> list[np.ndarray]:
    cap = cv2.VideoCapture(str(path))
    got = []
    while True:
        ok, img = cap.read()
        if not ok:
            return got
        got.append(img)


@pytest.mark.parametrize("backend, size", [
    ("pyav", (96, 64)),
    ("pyav", (97, 63)),     # odd sizes are padded by one pixel for 4:2:0
    ("opencv", (96, 64)),
])
@pytest.mark.parametrize("codec", ["vp80", "vp90"])
def test_webm_round_trip(tmp_path, backend, codec, size):
    frames = _frames(12, *size)
    path = tmp_path / "v.webm"
    with VideoSink(path, 10.0, codec, backend=backend) as sink:
        assert sink.backend == backend
        for f in frames:
            sink.write(f)
        assert not path.exists()  # written under a temporary name until closed
    assert path.read_bytes()[:4] == b"\x1a\x45\xdf\xa3"  # EBML (WebM) magic
    assert [p.name for p in tmp_path.iterdir()] == ["v.webm"]
    got = _read(path)
    assert len(got) == len(frames)
    w, h = size
    assert got[0].shape[0] >= h and got[0].shape[1] >= w
    for a, b in zip(frames, got):
        diff = np.abs(a.astype(int) - b[:h, :w].astype(int)).mean()
        assert diff < 12, diff  # lossy, but the same picture


def test_auto_uses_pyav_for_webm_only(tmp_path):
    assert VideoSink(tmp_path / "a.webm", 25, "vp80").backend == "pyav"
    assert VideoSink(tmp_path / "a.webm", 25, "vp90").backend == "pyav"
    assert VideoSink(tmp_path / "a.avi", 25, "mjpg").backend == "opencv"


def test_bad_backend_and_codec_combinations(tmp_path):
    with pytest.raises(InputError, match="backend"):
        VideoSink(tmp_path / "a.webm", 25, "vp80", backend="gstreamer")
    with pytest.raises(InputError, match="pyav backend"):
        VideoSink(tmp_path / "a.avi", 25, "mjpg", backend="pyav")


def test_no_frames_no_file(tmp_path):
    with VideoSink(tmp_path / "a.webm", 25, "vp80"):
        pass
    assert list(tmp_path.iterdir()) == []


def test_outputs_get_the_usual_permissions_not_mkstemps_0600(tmp_path):
    import importlib
    import os
    import stat

    import motiontrack.io.atomic as atomic

    old = os.umask(0o022)
    try:
        importlib.reload(atomic)  # FILE_MODE is taken from the umask at import (same module dict)
        assert atomic.FILE_MODE == 0o644
        atomic.atomic_write_text(tmp_path / "a.txt", "x\n")
        with VideoSink(tmp_path / "v.webm", 10.0, "vp80") as sink:
            sink.write(_frames(1, 32, 32)[0])
    finally:
        os.umask(old)
        importlib.reload(atomic)
    assert stat.S_IMODE((tmp_path / "a.txt").stat().st_mode) == 0o644
    assert stat.S_IMODE((tmp_path / "v.webm").stat().st_mode) == 0o644
