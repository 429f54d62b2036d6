"""The video encoder in its own thread: every frame reaches the file in order, the queue between
the run and the encoder is bounded, an encoder failure is one clear error, and a run that stops or
fails mid-way leaves a complete playable file or none (io/frame_queue.py, io/video.py)."""

from __future__ import annotations

import json
import threading

import numpy as np
import pytest

from motiontrack.cli import main
from motiontrack.config import load_config
from motiontrack.io import video
from motiontrack.io.frame_queue import FrameQueue, slots_for
from motiontrack.io.sources import open_source
from motiontrack.io.video import EncoderError, VideoSink
from motiontrack.pipeline import open_configured_source
from motiontrack.run import Job
from motiontrack.run.processors import TrackProcessor
from motiontrack.run.writers import TracksWriter, VideoWriter
from helpers.video_files import read_frames


def _numbered(n: int, w: int = 96, h: int = 64) -> list[np.ndarray]:
    """Frames whose number k is a white bar k * 4 px from the left on black."""
    out = []
    for k in range(n):
        img = np.zeros((h, w, 3), np.uint8)
        x = 4 * k % (w - 4)
        img[:, x:x + 4] = 255
        out.append(img)
    return out


def _bar_positions(path) -> list[int]:
    """The column of the white bar in each decoded frame."""
    return [int(np.argmax(img[:, :, 1].mean(axis=0) > 128)) for img in read_frames(path)]


@pytest.mark.parametrize("codec, backend", [("vp80", "pyav"), ("h264", "pyav"),
                                            ("vp80", "opencv"), ("mjpg", "opencv")])
def test_every_frame_written_is_in_the_file_in_order(tmp_path, codec, backend):
    if backend == "pyav" and video.pyav_encoder(codec) is None:
        pytest.skip(f"this PyAV has no {codec} encoder")
    frames = _numbered(40)
    path = tmp_path / f"v{video.extension_for(codec)}"
    with VideoSink(path, 10.0, codec, backend=backend) as sink:
        for f in frames:
            sink.write(f)
    assert _bar_positions(path) == [4 * k % 92 for k in range(40)]


def test_frames_are_encoded_in_another_thread(tmp_path, monkeypatch):
    threads = set()
    real = video._PyAVWriter.write

    def write(self, image):
        threads.add(threading.current_thread().name)
        real(self, image)

    monkeypatch.setattr(video._PyAVWriter, "write", write)
    with VideoSink(tmp_path / "v.webm", 10.0, "vp80") as sink:
        for f in _numbered(5):
            sink.write(f)
    assert threads == {"motiontrack-video-v.webm"}


def test_the_queue_holds_at_most_its_slots_and_writing_waits_for_a_free_one():
    release = threading.Event()
    consumed = []

    def consume(frame):
        release.wait()
        consumed.append(int(frame[0, 0, 0]))

    q = FrameQueue(consume, (8, 8, 3), slots=3)
    for k in range(3):                    # the worker holds one, two wait: every buffer in use
        q.put(np.full((8, 8, 3), k, np.uint8))
    assert q.pending == 3
    fourth = threading.Thread(target=q.put, args=(np.full((8, 8, 3), 3, np.uint8),))
    fourth.start()
    fourth.join(timeout=0.3)
    assert fourth.is_alive()              # blocked: no fourth buffer exists
    assert q.pending == 3
    release.set()
    fourth.join()
    q.close()
    assert consumed == [0, 1, 2, 3]
    assert q.pending == 0


def test_queued_frames_are_copies_so_the_run_may_draw_on_its_image_again():
    release = threading.Event()
    consumed = []
    q = FrameQueue(lambda f: (release.wait(), consumed.append(int(f[0, 0, 0]))), (4, 4, 3), slots=2)
    img = np.zeros((4, 4, 3), np.uint8)
    q.put(img)
    img[:] = 9                            # the run reuses its image before the encoder ran
    q.put(img)
    release.set()
    q.close()
    assert consumed == [0, 9]


def test_gray_frames_are_queued_as_bgr():
    got = []
    q = FrameQueue(lambda f: got.append(f.copy()), (2, 3, 3), slots=2)
    q.put(np.array([[0, 255, 7], [1, 2, 3]], np.uint8))
    q.close()
    assert got[0].shape == (2, 3, 3) and (got[0][..., 0] == got[0][..., 2]).all()
    assert got[0][0, :, 1].tolist() == [0, 255, 7]


def test_large_frames_get_fewer_buffers_but_at_least_two():
    assert slots_for((576, 768, 3)) == 4
    assert slots_for((2160, 3840, 3)) == 2
    assert slots_for((8640, 15360, 3)) == 2


def test_an_encoder_failure_is_raised_once_as_one_clear_error(tmp_path, monkeypatch):
    calls = []

    def write(self, image):
        calls.append(1)
        if len(calls) == 3:
            raise RuntimeError("Generic error in an external library")

    monkeypatch.setattr(video._PyAVWriter, "write", write)
    path = tmp_path / "v.webm"
    sink = VideoSink(path, 10.0, "vp80")
    with pytest.raises(EncoderError) as err:
        for f in _numbered(50):             # raised by a later write, once the thread has failed
            sink.write(f)
        sink.close()
    assert str(err.value) == (f"cannot encode vp80 video to {path}: "
                              "Generic error in an external library")
    sink.discard()                          # what a job does next: nothing more is raised
    assert list(tmp_path.iterdir()) == []
    assert len(calls) == 3                  # nothing was encoded after the failure


def test_a_frame_of_another_size_is_a_clear_error(tmp_path):
    sink = VideoSink(tmp_path / "v.webm", 10.0, "vp80")
    sink.write(np.zeros((64, 96, 3), np.uint8))
    with pytest.raises(EncoderError, match="frame of 48x32 pixels in a video of 96x64"):
        sink.write(np.zeros((32, 48, 3), np.uint8))
    sink.discard()
    assert list(tmp_path.iterdir()) == []


def test_an_encoder_failing_in_a_track_run_is_one_line_and_leaves_no_output(tmp_path, capsys,
                                                                            monkeypatch):
    def write(self, image):
        raise RuntimeError("encoder out of memory")

    monkeypatch.setattr(video._PyAVWriter, "write", write)
    out = tmp_path / "o"
    code = main(["track", "synth:walker?n_frames=30", "-o", str(out), "-q"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.strip().splitlines() == [
        f"motiontrack: error: cannot encode vp80 video to {out / 'annotated.webm'}: "
        "encoder out of memory"]
    assert not out.exists() or sorted(p.name for p in out.iterdir()) == []


def _track_job(out, codec="vp80"):
    cfg = load_config(None, [f'output.codec="{codec}"'])
    src = open_configured_source("synth:walker?n_frames=40", cfg.source)
    path = out / f"annotated{video.extension_for(codec)}"
    writers = [TracksWriter(out), VideoWriter("video", path, codec)]
    return Job(src, TrackProcessor(cfg, src.info), writers, out), path


def _slow_encoder(monkeypatch) -> None:
    """PyAV's writer takes 20 ms more a frame: frames are still queued when a run ends."""
    real = video._PyAVWriter.write
    monkeypatch.setattr(video._PyAVWriter, "write",
                        lambda self, image: (threading.Event().wait(0.02), real(self, image)))


def test_a_stop_mid_run_leaves_a_playable_video_of_every_finished_frame(tmp_path, monkeypatch):
    _slow_encoder(monkeypatch)
    out = tmp_path / "o"
    job, path = _track_job(out)
    seen = []

    def stop() -> bool:
        seen.append(1)
        return len(seen) == 17

    with pytest.raises(KeyboardInterrupt):
        job.run(should_stop=stop)
    assert json.loads((out / "summary.json").read_text())["frames"] == 17
    import av

    with av.open(str(path)) as c:
        assert sum(1 for _ in c.decode(video=0)) == 17
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]


def test_a_run_failing_while_frames_are_queued_leaves_no_video(tmp_path, monkeypatch):
    _slow_encoder(monkeypatch)
    out = tmp_path / "o"
    job, path = _track_job(out)
    failing = TracksWriter.write

    def write(self, result):
        if result.index == 20:
            raise RuntimeError("a bug")
        failing(self, result)

    monkeypatch.setattr(TracksWriter, "write", write)
    with pytest.raises(RuntimeError, match="a bug"):
        job.run()
    assert not out.exists() or list(out.iterdir()) == []    # no video, no temporary file


def test_the_mask_video_of_gray_frames_has_every_frame(tmp_path):
    out = tmp_path / "o"
    assert main(["track", "synth:walker?n_frames=25", "-o", str(out), "--mask-video", "-q"]) == 0
    import av

    with av.open(str(out / "mask.webm")) as c:
        assert sum(1 for _ in c.decode(video=0)) == 25
    info = open_source("synth:walker?n_frames=25").info
    with av.open(str(out / "annotated.webm")) as c:
        s = c.streams.video[0]
        assert (s.codec_context.width, s.codec_context.height) == (info.width, info.height)


def test_webm_through_opencv_says_how_to_encode_it_faster(tmp_path, monkeypatch, caplog):
    monkeypatch.setattr(video, "pyav_encoder", lambda codec: None)    # an installation without PyAV
    caplog.set_level("INFO", logger="motiontrack.io.video")
    with VideoSink(tmp_path / "v.webm", 10.0, "vp80") as sink:
        assert sink.backend == "opencv"
        sink.write(_numbered(1)[0])
    assert "v.webm: vp80 is encoded by OpenCV" in caplog.text
    assert "pip install 'motiontrack[video]'" in caplog.text
    caplog.clear()
    with VideoSink(tmp_path / "v.avi", 10.0, "mjpg") as sink:
        sink.write(_numbered(1)[0])
    assert caplog.text == ""
