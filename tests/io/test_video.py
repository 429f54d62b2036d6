"""Video sinks: WebM through PyAV (fast real-time libvpx) or OpenCV, H.264 MP4, atomic files, odd
sizes, and the codecs this installation can encode."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiontrack.cli import main
from motiontrack.errors import InputError
from motiontrack.io import video
from motiontrack.io.sources import open_source
from motiontrack.io.video import VideoSink
from helpers.video_files import read_frames

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
    got = read_frames(path)
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
    # the module's own objects are put back afterwards: a reload makes new classes (DiskFullError)
    # that the modules which imported the old ones would not catch
    saved = dict(vars(atomic))
    try:
        importlib.reload(atomic)  # FILE_MODE is taken from the umask at import (same module dict)
        assert atomic.FILE_MODE == 0o644
        atomic.atomic_write_text(tmp_path / "a.txt", "x\n")
        with VideoSink(tmp_path / "v.webm", 10.0, "vp80") as sink:
            sink.write(_frames(1, 32, 32)[0])
    finally:
        os.umask(old)
        vars(atomic).clear()
        vars(atomic).update(saved)
    assert stat.S_IMODE((tmp_path / "a.txt").stat().st_mode) == 0o644
    assert stat.S_IMODE((tmp_path / "v.webm").stat().st_mode) == 0o644


# ------------------------------------------------------------------------------- codecs
def _decode(path):
    """(codec name, pixel format, width, height, frames) of the video stream, decoded by PyAV."""
    import av

    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        ctx = stream.codec_context
        n = sum(1 for _ in container.decode(stream))
        return ctx.name, ctx.pix_fmt, ctx.width, ctx.height, n


def test_h264_is_a_browser_playable_mp4(tmp_path):
    if video.pyav_encoder("h264") is None:
        pytest.skip("this PyAV has no H.264 encoder")
    path = tmp_path / "v.mp4"
    with VideoSink(path, 10.0, "h264") as sink:
        assert sink.backend == "pyav"
        for f in _frames(30, 96, 64):
            sink.write(f)
    assert _decode(path) == ("h264", "yuv420p", 96, 64, 30)
    data = path.read_bytes()
    assert data[4:8] == b"ftyp"
    assert data.index(b"moov") < data.index(b"mdat")     # faststart: the index comes first


def test_a_track_run_writes_h264_at_the_source_size(tmp_path, capsys):
    if "h264" not in video.encodable_codecs():
        pytest.skip("this installation cannot encode H.264")
    spec = "synth:walker?n_frames=20"
    assert main(["track", spec, "--codec", "h264", "-o", str(tmp_path / "o")]) == 0
    info = open_source(spec).info
    assert _decode(tmp_path / "o" / "annotated.mp4") == ("h264", "yuv420p", info.width,
                                                         info.height, 20)


def test_every_codec_listed_as_encodable_encodes(tmp_path):
    listed = video.encodable_codecs()
    assert {"vp80", "vp90"} <= set(listed)                # PyAV is installed with the dev extras
    for codec in listed:
        path = tmp_path / f"{codec}{video.extension_for(codec)}"
        with VideoSink(path, 10.0, codec) as sink:
            for f in _frames(5, 64, 48):
                sink.write(f)
        assert len(read_frames(path)) == 5, codec


@pytest.fixture
def without_xvid_and_h264(monkeypatch):
    """An installation whose OpenCV cannot write Xvid and whose PyAV has no H.264 encoder."""
    real_cv, real_av = video.opencv_encodes, video.pyav_encoder
    monkeypatch.setattr(video, "opencv_encodes",
                        lambda c: c not in ("xvid", "h264", "avc1") and real_cv(c))
    monkeypatch.setattr(video, "pyav_encoder", lambda c: None if c == "h264" else real_av(c))


def test_list_and_codec_help_name_only_what_this_installation_encodes(without_xvid_and_h264,
                                                                      capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    section = out[out.index("video codecs"):].split("\n\n")[0].splitlines()
    names = [ln.split()[0] for ln in section[1:] if ln.startswith("  ")]
    assert "vp80" in names and "mjpg" in names
    assert not {"xvid", "h264", "avc1"} & set(names)
    with pytest.raises(SystemExit):
        main(["track", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "can encode: vp80, vp90, mp4v, mjpg (default vp80" in help_text


@pytest.mark.parametrize("codec, message", [
    ("xvid", "this installation cannot encode xvid video; it can encode: vp80, vp90, mp4v, mjpg"),
    ("h264", "cannot encode h264 video (it needs PyAV with libx264 or OpenH264"),
    ("divx", "unknown codec 'divx'; this installation can encode: vp80, vp90, mp4v, mjpg"),
])
@pytest.mark.parametrize("command", ["track", "flow", "follow"])
def test_a_codec_this_installation_cannot_encode_is_one_clear_error(
        without_xvid_and_h264, tmp_path, capsys, codec, message, command):
    extra = ["--box", "10,10,20,40"] if command == "follow" else []
    code = main([command, "synth:walker?n_frames=5", "--codec", codec, "-o", str(tmp_path / "o"),
                 *extra])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and message in err, err
    assert not (tmp_path / "o").exists()
