"""``track --show`` with OpenCV's headless build: the serve page of the one source on 127.0.0.1,
fed by the track job, which keeps its outputs and its Ctrl-C rules, answering only to the host
names of 127.0.0.1 and of ``--allowed-host``."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

pytest.importorskip("starlette")
pytest.importorskip("uvicorn")
httpx = pytest.importorskip("httpx")

from helpers import free_port  # noqa: E402
from motiontrack.io.mot import read_mot  # noqa: E402


def _headless() -> bool:
    info = cv2.getBuildInformation()
    line = next((ln for ln in info.splitlines() if ln.strip().startswith("GUI:")), "GUI: NONE")
    return "NONE" in line.upper()


pytestmark = pytest.mark.skipif(not _headless(), reason="OpenCV's GUI build shows a window")


class Track:
    """``motiontrack track SOURCE --show --port P`` in a subprocess without a display."""

    def __init__(self, tmp_path: Path, source: str, *more: str) -> None:
        self.port, self.out = free_port(), tmp_path / "run"
        self.err = open(tmp_path / "stderr.txt", "w+")
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        for k in ("DISPLAY", "WAYLAND_DISPLAY"):   # no browser is opened
            env.pop(k, None)
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "motiontrack", "track", source, "--show", "--port",
             str(self.port), "--no-video", "-o", str(self.out), *more],
            stdout=subprocess.PIPE, stderr=self.err, env=env, text=True)
        self.client = httpx.Client(base_url=f"http://127.0.0.1:{self.port}", timeout=5)

    def stderr(self) -> str:
        self.err.flush()
        return Path(self.err.name).read_text()

    def poll(self, cond, timeout: float, what: str):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            assert self.proc.poll() is None, self.stderr()
            try:
                got = cond()
            except httpx.TransportError:
                got = None
            if got:
                return got
            time.sleep(0.05)
        raise AssertionError(f"not within {timeout} s: {what}\n{self.stderr()}")

    def camera(self) -> dict:
        (cam,) = self.client.get("/api/cameras").json()
        return cam

    def interrupt(self) -> tuple[int, str]:
        self.proc.send_signal(signal.SIGINT)
        out, _ = self.proc.communicate(timeout=30)
        return self.proc.returncode, out

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)
        self.client.close()
        self.err.close()


@pytest.fixture
def track(tmp_path):
    runs = []

    def start(source: str, *more: str) -> Track:
        runs.append(Track(tmp_path, source, *more))
        return runs[-1]

    yield start
    for t in runs:
        t.close()


@pytest.mark.slow
def test_headless_show_serves_the_page_of_the_running_source(track):
    t = track("synth:walker?n_frames=5000", "--allowed-host", "cams.lan")
    cam = t.poll(lambda: (lambda c: c if c["status"] == "running" and c["frames"] > 10 else None)
                 (t.camera()), 60, "the camera running")
    assert cam["name"] == "synth-walker" and cam["fps"] > 0 and cam["scene"] is False
    r = t.client.get("/api/cameras/synth-walker/snapshot.jpg")
    assert r.status_code == 200 and r.headers["content-type"] == "image/jpeg"
    img = cv2.imdecode(np.frombuffer(r.content, np.uint8), cv2.IMREAD_COLOR)
    assert img.shape == (480, 640, 3)
    assert 0 <= time.time() - float(r.headers["x-frame-wall"]) < 5   # when its frame was read
    page = t.client.get("/")
    assert page.status_code == 200 and "text/html" in page.headers["content-type"]
    assert f"live view: http://127.0.0.1:{t.port}/" in t.stderr()
    # the names of 127.0.0.1 and --allowed-host's, not a name rebound to 127.0.0.1
    for host, status in ((f"localhost:{t.port}", 200), (f"cams.lan:{t.port}", 200),
                         (f"evil.example:{t.port}", 403)):
        assert t.client.get("/api/cameras", headers={"Host": host}).status_code == status, host
    frames_then = t.camera()["frames"]
    # still counting, and past the frames where the walker is first tracked (28 to 32) on a
    # machine too busy to play the source at its rate
    t.poll(lambda: t.camera()["frames"] > max(frames_then, 60), 30, "frames still counting")

    code, out = t.interrupt()
    assert code in (0, 130), t.stderr()
    summary = json.loads((t.out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and 10 < summary["frames"] < 5000
    tracks = read_mot(t.out / "tracks.txt")
    assert len(tracks) > 0 and tracks.frames.max() <= summary["frames"]
    assert "Traceback" not in t.stderr()


@pytest.mark.slow
def test_headless_show_keeps_the_page_after_the_run_until_ctrl_c(track):
    t = track("synth:walker?n_frames=40")
    t.poll(lambda: "run finished" in t.stderr(), 60, "the run finished")
    cam = t.camera()
    assert (cam["status"], cam["frames"]) == ("ended", 40)
    assert t.client.get("/api/cameras/synth-walker/snapshot.jpg").status_code == 200
    code, out = t.interrupt()
    assert code == 0, t.stderr()
    assert "frames    40" in out
    summary = json.loads((t.out / "summary.json").read_text())
    assert (summary["status"], summary["frames"]) == ("complete", 40)


#: the walker's scene: a line across its path, a zone over the right half
WALKER_SCENE = """\
# the walker's street
[[line]]
name = "middle"   # halfway
points = [[320, 0], [320, 480]]

[[zone]]
name = "right"
polygon = [[330, 0], [640, 0], [640, 480], [330, 480]]
"""


@pytest.mark.slow
def test_headless_show_plays_a_file_at_its_rate_and_keeps_page_and_scene_after_it(
        track, tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(WALKER_SCENE)
    # 50 frames at the walker's 25 fps: two seconds shown, not the fraction of a second it
    # takes to process them
    t = track("synth:walker?n_frames=50", "--scene", str(scene))
    t.poll(lambda: "run finished" in t.stderr(), 60, "the run finished")
    summary = json.loads((t.out / "summary.json").read_text())
    assert summary["frames"] == 50 and summary["seconds"] >= 49 / 25 - 0.05
    cam = t.camera()
    assert (cam["status"], cam["scene"]) == ("ended", True)
    name = cam["name"]
    events = t.client.get(f"/api/cameras/{name}/events").json()
    assert [e["type"] for e in events] == ["zone_enter"]
    # the page shows the finished run: the last picture as a still, the events in the feed
    _page_after_the_run(t, name, len(events))
    # the editor edits the run's scene file: the line moves, the comments stay
    got = t.client.get(f"/api/cameras/{name}/scene")
    assert got.status_code == 200 and got.json()["lines"][0]["name"] == "middle"
    edit = {**got.json()}
    edit["lines"] = [{"name": "middle", "points": [[300, 0], [300, 480]]}]
    assert t.client.put(f"/api/cameras/{name}/scene", json=edit).status_code == 200
    assert scene.read_text() == WALKER_SCENE.replace("[[320, 0], [320, 480]]",
                                                     "[[300, 0], [300, 480]]")
    code, _ = t.interrupt()
    assert code == 0, t.stderr()


def _page_after_the_run(t: Track, name: str, n_events: int) -> None:
    """The page opened after the run: its tile holds a picture and its feed the events."""
    from helpers.browser import chromium

    driver = chromium("1200,900")
    try:
        driver.get(f"http://127.0.0.1:{t.port}/")
        t.poll(lambda: driver.execute_script(
            "const img = document.querySelector(`[data-testid=\"camera-img-${arguments[0]}\"]`);"
            "return img && img.complete && img.naturalWidth > 0;", name), 15,
            "the tile's picture")
        t.poll(lambda: len(driver.find_elements("css selector", '[data-testid="event"]'))
               == n_events, 15, "the run's events in the feed")
        shot = driver.find_element("css selector", f'[data-testid="camera-img-{name}"]')
        img = cv2.imdecode(np.frombuffer(shot.screenshot_as_png, np.uint8), cv2.IMREAD_COLOR)
        assert img.mean() > 20   # the walker's street, not a black tile
        errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
        assert not errors, errors
    finally:
        driver.quit()
