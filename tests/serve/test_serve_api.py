"""``motiontrack serve``: the JSON API, the streams, the scene editor's writes, the token, the
camera processes' supervision and their outputs.

The app's request handling (token, sizes, unknown cameras, scene validation) is tested in
process over a hub without cameras; the live behaviour against a ``motiontrack serve`` process
on a free 127.0.0.1 port with two looping synthetic cameras (walker and crossing, their scene
files from ``motiontrack synth-events``).
"""

from __future__ import annotations

import json
import os
import re
import signal
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("starlette")
pytest.importorskip("uvicorn")
httpx = pytest.importorskip("httpx")

from motiontrack.cli import main  # noqa: E402
from motiontrack.errors import ConfigError  # noqa: E402
from motiontrack.io.events import read_events  # noqa: E402
from motiontrack.io.mot import read_mot  # noqa: E402
from motiontrack.io.tomlfile import read_toml  # noqa: E402
from motiontrack.serve.cameras import parse_cameras  # noqa: E402
from helpers.serve_process import ServeProcess, synth_cameras  # noqa: E402

CAMERAS = ("walker", "crossing")
#: the base URL of in-process requests: a Host the app answers to
LOOPBACK = "http://127.0.0.1:8080"


# ----------------------------------------------------------------------------- cameras file
@pytest.mark.parametrize("data, message", [
    ({}, "lists no cameras"),
    ({"camera": [{"source": "synth:walker"}]}, "camera[1].name is required"),
    ({"camera": [{"name": "a b", "source": "x"}]}, "camera[1].name must be 1 to 40"),
    ({"camera": [{"name": "a"}]}, "camera[1].source is required"),
    ({"camera": [{"name": "a", "source": "x"}, {"name": "a", "source": "y"}]},
     "camera[2].name 'a' is used by an earlier camera"),
    ({"camera": [{"name": "a", "source": "x", "loop": "yes"}]}, "camera[1].loop must be true or false, got 'yes'"),
    ({"camera": [{"name": "a", "source": "x", "fps": 0}]}, "camera[1].fps must be in (0, 1000], got 0.0"),
    ({"camera": [{"name": "a", "source": "x", "speed": 0}]},
     "camera[1].speed must be in (0, 1000], got 0.0"),
    ({"camera": [{"name": "a", "source": "x", "sorce": "y"}]},
     "unknown key(s) camera[1].sorce; valid keys in camera[1]: camera, config, fps, loop, name"),
    ({"camera": [{"name": "a", "source": " "}]}, "camera[1].source must be a non-empty string"),
])
def test_cameras_file_problems_name_the_key(data, message):
    with pytest.raises(ConfigError, match=re.escape(message)):
        parse_cameras(data, "/base")


def test_an_event_stream_id_reads_back_or_is_ignored():
    from motiontrack.serve.hub import Cursor

    c = Cursor.parse("ab12.gate=12,lobby-2=40")
    assert c == Cursor("ab12", {"gate": 12, "lobby-2": 40}) and str(c) == "ab12.gate=12,lobby-2=40"
    assert Cursor.parse("ab12.") == Cursor("ab12", {})
    for junk in (None, "", "x", "ab12", "ab12.gate", "ab12.gate=-1", "AB.gate=1", "ab12.g=1\n",
                 "ab12.g=1;h=2"):
        assert Cursor.parse(junk) is None, junk


def test_cameras_file_paths_are_relative_to_the_file():
    (cam,) = parse_cameras({"camera": [{"name": "gate", "source": "clips/a.mp4",
                                        "scene": "gate.toml", "loop": True}]}, "/base")
    assert cam.source == "/base/clips/a.mp4"
    assert cam.scene == Path("/base/gate.toml")
    assert cam.loop is True
    (cam,) = parse_cameras({"camera": [{"name": "s", "source": "synth:walker"}]}, "/base")
    assert cam.source == "synth:walker"
    (cam,) = parse_cameras({"camera": [{"name": "r", "source": "rtsp://h/1"}]}, "/base")
    assert cam.source == "rtsp://h/1"


def test_non_local_bind_without_token_is_refused(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("MOTIONTRACK_TOKEN", raising=False)
    cams = tmp_path / "cameras.toml"
    cams.write_text('[[camera]]\nname = "a"\nsource = "synth:walker"\n')
    assert main(["serve", str(cams), "--host", "0.0.0.0", "--port", "1"]) == 2
    err = capsys.readouterr().err
    assert "--token" in err and "Traceback" not in err


# --------------------------------------------------------------------------- app in process
def _app(tmp_path, token=None):
    from motiontrack.serve.app import create_app
    from motiontrack.serve.hub import Hub

    scene = tmp_path / "scene.toml"
    scene.write_text('anchor = "center"\n[[line]]\nname = "gate"\npoints = [[0, 0], [10, 10]]\n')
    hub = Hub([("cam", True), ("plain", False)])
    return create_app(hub, token, {"cam": scene, "plain": None}), hub, scene


class _Client:
    """Requests to an ASGI app in process (httpx's ASGI transport), one event loop each."""

    def __init__(self, app) -> None:
        self.app = app

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass

    def request(self, method: str, url: str, **kw):
        import asyncio

        async def go():
            transport = httpx.ASGITransport(app=self.app)
            # the app answers to the names of a loopback address (Host: 127.0.0.1:8080)
            async with httpx.AsyncClient(transport=transport, base_url=LOOPBACK) as c:
                return await c.request(method, url, **kw)

        return asyncio.run(go())

    def get(self, url: str, **kw):
        return self.request("GET", url, **kw)

    def put(self, url: str, **kw):
        return self.request("PUT", url, **kw)


def _client(app):
    return _Client(app)


ROUTES = ["/", "/static/app.js", "/static/style.css", "/api/cameras",
          "/api/cameras/cam/events?since=0", "/api/cameras/cam/counts",
          "/api/cameras/cam/snapshot.jpg", "/api/cameras/cam/stream.mjpg",
          "/api/cameras/cam/scene", "/api/events", "/api/schema/scene", "/api/schema/cameras"]


def test_token_is_required_on_every_route(tmp_path):
    app, _, _ = _app(tmp_path, token="s3cret")
    with _client(app) as c:
        for route in ROUTES:
            assert c.get(route).status_code == 401, route
            assert c.get(route, headers={"Authorization": "Bearer wrong"}).status_code == 401
        assert c.put("/api/cameras/cam/scene", json={}).status_code == 401
        ok = c.get("/api/cameras", headers={"Authorization": "Bearer s3cret"})
        assert ok.status_code == 200 and [x["name"] for x in ok.json()] == ["cam", "plain"]
        assert c.get("/api/cameras?token=s3cret").status_code == 200
        assert c.get("/?token=s3cret").status_code == 200


def test_file_schemas_are_served_as_exported_and_revalidated_by_etag(tmp_path):
    from motiontrack.analytics.scene import scene_json_schema
    from motiontrack.serve.cameras import cameras_json_schema

    app, _, _ = _app(tmp_path, token="s3cret")
    auth = {"Authorization": "Bearer s3cret"}
    with _client(app) as c:
        for name, exported in (("scene", scene_json_schema()), ("cameras", cameras_json_schema())):
            r = c.get(f"/api/schema/{name}", headers=auth)
            assert r.status_code == 200 and r.headers["content-type"] == "application/json"
            assert r.json() == exported
            assert "no-cache" in r.headers["cache-control"]
            etag = r.headers["etag"]
            # the same tag again (also weak, also in a list): 304 without a body
            for asked in (etag, f"W/{etag}", f'"other", {etag}'):
                again = c.get(f"/api/schema/{name}", headers={**auth, "If-None-Match": asked})
                assert again.status_code == 304 and again.content == b"", asked
                assert again.headers["etag"] == etag
            assert c.get(f"/api/schema/{name}", headers={**auth, "If-None-Match": '"other"'}
                         ).status_code == 200
            # the token is checked before the cache: a known tag without it is still 401
            assert c.get(f"/api/schema/{name}", headers={"If-None-Match": etag}).status_code == 401
        assert c.get("/api/schema/scene?token=s3cret").json() == scene_json_schema()
        assert c.get("/api/schema/scene.toml", headers=auth).status_code == 404
        assert c.get("/api/schema/..%2Fapp.py", headers=auth).status_code == 404


def test_unknown_camera_is_404_and_no_path_reaches_the_files(tmp_path):
    app, _, _ = _app(tmp_path)
    with _client(app) as c:
        for route in ("/api/cameras/nope/counts", "/api/cameras/nope/events",
                      "/api/cameras/nope/snapshot.jpg", "/api/cameras/nope/scene",
                      "/api/cameras/nope/stream.mjpg", "/static/..%2Fapp.py",
                      "/static/cameras.py"):
            assert c.get(route).status_code == 404, route
        assert c.get("/api/cameras/cam/snapshot.jpg").status_code == 404   # no picture yet
        assert c.get("/api/cameras/cam/events?since=x").status_code == 400


def test_oversized_body_is_413(tmp_path):
    app, _, scene = _app(tmp_path)
    before = scene.read_text()
    with _client(app) as c:
        r = c.put("/api/cameras/cam/scene", content=b"{" + b" " * (64 * 1024) + b"}")
        assert r.status_code == 413
    assert scene.read_text() == before


def test_scene_put_is_validated_and_keeps_other_settings(tmp_path):
    app, _, scene = _app(tmp_path)
    with _client(app) as c:
        got = c.get("/api/cameras/cam/scene").json()
        assert got["lines"] == [{"name": "gate", "points": [[0, 0], [10, 10]]}]
        bad = [{"lines": [{"name": "x", "points": [[0, 0]]}]},               # one point
               {"zones": [{"name": "z", "polygon": [[0, 0], [1, 1], [0, 1], [1, 0]]}]},  # bow tie
               {"lines": [{"name": "x", "points": [[0, 0], [1, None]]}]},
               {"lines": "gate"}, [1, 2]]
        for body in bad:
            r = c.put("/api/cameras/cam/scene", json=body)
            assert r.status_code == 400 and r.json()["error"], body
        assert c.put("/api/cameras/cam/scene", content=b"not json").status_code == 400
        assert read_toml(scene)["line"][0]["name"] == "gate"   # untouched
        new = {"lines": [{"name": "gate", "points": [[0, 0], [10, 10]]},
                         {"name": "door", "points": [[5, 0], [5, 9]]}],
               "zones": [{"name": "hall", "polygon": [[0, 0], [9, 0], [9, 9]], "loiter_s": 4}],
               "width": 640, "height": 480}
        r = c.put("/api/cameras/cam/scene", json=new)
        assert r.status_code == 200
        data = read_toml(scene)
        assert [ln["name"] for ln in data["line"]] == ["gate", "door"]
        assert data["zone"][0]["loiter_s"] == 4
        assert data["anchor"] == "center"               # the file's other settings stay
        assert "width" not in data
        assert [p.name for p in tmp_path.iterdir()] == ["scene.toml"]   # no temporary left
        assert c.put("/api/cameras/plain/scene", json=new).status_code == 409


#: a scene written by hand: comments, blank lines, aligned values, keys in its own order
HAND_SCENE = """\
# Gate camera, main entrance.
anchor = "bottom_center"    # feet on the ground
forget_s = 3.0

# -- counting ------------------------------------------------------------
[[line]]
name   = "gate"                         # the turnstiles
points = [[100, 400], [540, 400]]       # left to right: in = walking down

[[line]]
name   = "side-door"
points = [[600, 100], [600, 300]]

# -- waiting -------------------------------------------------------------
[[zone]]
name     = "queue"
polygon  = [[80, 300], [300, 300], [300, 470], [80, 470]]
loiter_s = 30.0                         # half a minute is loitering

[stationary]
after_s   = 10.0
radius_px = 12
"""


def test_saving_an_edited_scene_keeps_the_hand_written_rest_byte_for_byte(tmp_path):
    from motiontrack.serve.scenes import SceneFiles

    scene = tmp_path / "scene.toml"
    scene.write_text(HAND_SCENE)
    files = SceneFiles({"cam": scene})
    view = files.read("cam")
    view["lines"][0]["points"] = [[100, 410], [540, 410]]      # the gate moved 10 px down
    files.write("cam", view)
    expected = HAND_SCENE.replace("points = [[100, 400], [540, 400]]       #",
                                  "points = [[100, 410], [540, 410]]       #")
    assert expected != HAND_SCENE and scene.read_text() == expected
    # a line added and the side door removed: the other tables and every comment stay
    view["lines"] = [view["lines"][0], {"name": "exit", "points": [[0, 0], [10, 10]]}]
    files.write("cam", view)
    text = scene.read_text()
    assert "side-door" not in text and 'name = "exit"' in text
    for kept in ("# Gate camera, main entrance.", "# feet on the ground", "# the turnstiles",
                 "loiter_s = 30.0                         # half a minute is loitering",
                 "[stationary]\nafter_s   = 10.0\nradius_px = 12\n"):
        assert kept in text
    assert [ln["name"] for ln in read_toml(scene)["line"]] == ["gate", "exit"]


def test_scene_edits_in_metres_are_checked_with_the_cameras_calibration(tmp_path, data):
    from motiontrack.calibrate import load_camera
    from motiontrack.serve.scenes import SceneFiles, check_scene_files

    xml = data("pets09-s2l1", "View_001.xml")
    # the example scene's west line, on the ground plane (metres)
    world = load_camera(xml).image_to_world([[300, 320], [300, 190]]).round(3).tolist()
    scene = tmp_path / "scene.toml"
    scene.write_text('anchor = "bottom_center"\n')
    edit = {"lines": [{"name": "west", "world": world}]}
    with pytest.raises(ConfigError, match="needs a camera"):
        SceneFiles({"pets": scene}).write("pets", edit)        # no calibration: refused
    files = SceneFiles({"pets": scene}, {"pets": xml})
    saved = files.write("pets", edit, (768, 576))
    assert saved["lines"] == [{"name": "west", "world": world}]
    assert read_toml(scene)["anchor"] == "bottom_center"
    check_scene_files({"pets": scene}, {"pets": xml})           # the server starts with it
    with pytest.raises(ConfigError, match="world"):             # one point is no line
        files.write("pets", {"lines": [{"name": "west", "world": world[:1]}]}, (768, 576))
    assert read_toml(scene)["line"][0]["world"] == world        # the file is unchanged


# ------------------------------------------------------------------------- a live server
def _serve(root: Path, *args: str) -> ServeProcess:
    """``motiontrack serve`` with the cameras walker and crossing, looping with their scenes."""
    return ServeProcess(root, synth_cameras(root, {n: f"synth:{n}" for n in CAMERAS}), *args)


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with _serve(tmp_path_factory.mktemp("serve")) as srv:
        srv.wait_running(frames=5, timeout=60)
        yield srv


def _mjpeg_frames(client, url: str, n: int, timeout: float = 10.0) -> list[bytes]:
    frames, buf = [], b""
    end = time.monotonic() + timeout
    with client.stream("GET", url) as r:
        assert r.status_code == 200
        assert r.headers["content-type"].startswith("multipart/x-mixed-replace; boundary=frame")
        for chunk in r.iter_bytes():
            buf += chunk
            while True:
                head = buf.find(b"\r\n\r\n")
                if not buf.startswith(b"--frame\r\n") or head < 0:
                    break
                length = int([h for h in buf[:head].split(b"\r\n")
                              if h.lower().startswith(b"content-length:")][0].split(b":")[1])
                if len(buf) < head + 4 + length + 2:
                    break
                frames.append(buf[head + 4:head + 4 + length])
                buf = buf[head + 4 + length + 2:]
            if len(frames) >= n or time.monotonic() > end:
                break
    return frames


@pytest.mark.slow
def test_live_pictures_snapshot_and_mjpeg(server):
    import cv2

    for name in CAMERAS:
        r = server.client.get(f"/api/cameras/{name}/snapshot.jpg")
        assert r.status_code == 200 and r.headers["content-type"] == "image/jpeg"
        img = cv2.imdecode(np.frombuffer(r.content, np.uint8), cv2.IMREAD_COLOR)
        assert img is not None and img.shape[2] == 3 and img.shape[0] > 100
    frames = _mjpeg_frames(server.client, "/api/cameras/walker/stream.mjpg", 3)
    assert len(frames) >= 3
    assert all(cv2.imdecode(np.frombuffer(f, np.uint8), cv2.IMREAD_COLOR) is not None
               for f in frames)
    cam = server.camera("walker")
    assert cam["fps"] > 5 and cam["reconnects"] == 0 and cam["scene"] is True


def _sse(client, n_events: int, headers: dict | None = None, timeout: float = 30.0
         ) -> tuple[str, list[tuple[str, dict]]]:
    """The stream's first id (where it starts) and its first ``n_events`` messages as
    ``(id, event)``, from ``/api/events``."""
    start, got, current = None, [], None
    end = time.monotonic() + timeout
    with client.stream("GET", "/api/events", headers=headers or {}, timeout=timeout) as r:
        assert r.headers["content-type"].startswith("text/event-stream")
        for line in r.iter_lines():
            if line.startswith("id: "):
                current = line[4:]
                start = start or current
            elif line.startswith("data: "):
                got.append((current, json.loads(line[6:])))
            if (start is not None and len(got) >= n_events) or time.monotonic() > end:
                break
    return start, got


@pytest.mark.slow
def test_live_events_since_sse_and_counts(server):
    # walker's person enters the plaza at frame 95 and crosses the gate at frame 139 (25 fps)
    events = server.wait("two walker events",
                         lambda: server.client.get("/api/cameras/walker/events?since=0").json()
                         if len(server.client.get("/api/cameras/walker/events?since=0").json()) >= 2
                         else None, 30)
    seqs = [e["seq"] for e in events]
    assert seqs == list(range(1, len(seqs) + 1))
    assert {e["type"] for e in events} >= {"zone_enter", "line_cross"}
    assert all("frame" in e and "t" in e and "track" in e and "wall" in e for e in events)
    # the walker's events name its track's class, and the camera lists its tracks with theirs
    assert {e.get("label") for e in events} == {"person"}
    listed = server.wait("walker's track listed as a person", lambda: next(
        (c["tracks"] for c in server.client.get("/api/cameras").json()
         if c["name"] == "walker" and any(t["class"] == "person" for t in c["tracks"])), None), 30)
    assert all(set(t) == {"id", "class"} for t in listed)
    later = server.client.get(f"/api/cameras/walker/events?since={seqs[0]}").json()
    assert [e["seq"] for e in later][:len(seqs) - 1] == seqs[1:]
    counts = server.client.get("/api/cameras/walker/counts").json()
    gate = counts["lines"]["gate"]
    crossings = sum(e["type"] == "line_cross" for e in
                    server.client.get("/api/cameras/walker/events?since=0").json())
    assert gate["in"] + gate["out"] >= crossings >= 1
    assert counts["zones"]["plaza"]["entered"] >= 1

    seen: dict[str, list[int]] = {}
    for _, e in _sse(server.client, 3, timeout=25)[1]:
        seen.setdefault(e["camera"], []).append(e["seq"])
    assert sum(len(v) for v in seen.values()) >= 3, seen
    for cam, s in seen.items():
        assert cam in CAMERAS and s == sorted(s) and len(set(s)) == len(s)


@pytest.mark.slow
def test_the_cameras_events_are_searchable_within_seconds(server):
    """Each camera process adds its events to the server's one store (OUT/events.db),
    committed within a second; the search API finds them by camera and type."""
    found = server.wait("the walker's events in the store",
                        lambda: (lambda r: r if r["total"] >= 2 else None)(server.client.get(
                            "/api/events/search?camera=walker").json()), 30)
    assert {e["camera"] for e in found["events"]} == {"walker"}
    assert all(e["segment"].startswith("walker/") for e in found["events"])
    assert {e["type"] for e in found["events"]} >= {"zone_enter", "line_cross"}
    crossings = server.client.get("/api/events/search?type=line_cross&rule=gate").json()
    assert crossings["total"] >= 1 and {e["rule"] for e in crossings["events"]} == {"gate"}
    assert (server.out / "events.db").is_file()


@pytest.mark.slow
def test_live_event_stream_resumes_where_the_last_one_ended(server):
    """What a browser's EventSource does when its connection drops: it reconnects with the id of
    the last message it received (Last-Event-ID), and the events it missed come first."""
    c = server.client
    start, _ = _sse(c, 0)
    seqs = dict(kv.split("=") for kv in start.split(".", 1)[1].split(","))
    assert set(seqs) == set(CAMERAS)
    walker = int(seqs["walker"])
    missed = server.wait("two walker events while no stream is open",
                         lambda: (lambda e: e if len(e) >= 2 else None)(
                             c.get(f"/api/cameras/walker/events?since={walker}").json()), 60)
    again, got = _sse(c, 2 * len(missed) + 2, headers={"Last-Event-ID": start})
    assert again == start                                   # it goes on from there
    by_camera: dict[str, list[int]] = {}
    for _, e in got:
        by_camera.setdefault(e["camera"], []).append(e["seq"])
    for cam, got_seqs in by_camera.items():                 # no gap, no repeat
        assert got_seqs == list(range(int(seqs[cam]) + 1, int(seqs[cam]) + 1 + len(got_seqs)))
    assert by_camera["walker"][:len(missed)] == [e["seq"] for e in missed]
    # every message's id is the cursor after it: a reconnection there goes on after it
    last_id, last = got[-1]
    assert f"{last['camera']}={last['seq']}" in last_id
    # another server's cursor (before a restart) or none: the stream starts now
    fresh, _ = _sse(c, 0, headers={"Last-Event-ID": "0." + start.split(".", 1)[1]})
    assert int(dict(kv.split("=") for kv in fresh.split(".", 1)[1].split(","))["walker"]) \
        >= walker + len(missed)


@pytest.mark.slow
def test_live_scene_edit_is_applied_without_restart(server):
    c = server.client
    scene = server.root / "walker" / "scene.toml"
    r = c.put("/api/cameras/walker/scene", json={"lines": [{"name": "bad", "points": [[1, 1]]}]})
    assert r.status_code == 400 and "points" in r.json()["error"]
    view = c.get("/api/cameras/walker/scene").json()
    assert view["width"] == 640 and view["height"] == 480
    pid = server.camera("walker")["pid"]
    view["lines"].append({"name": "middle", "points": [[100, 300], [540, 300]]})
    r = c.put("/api/cameras/walker/scene", json=view)
    assert r.status_code == 200
    assert [ln["name"] for ln in read_toml(scene)["line"]] == ["gate", "middle"]
    counts = server.wait("the new line in the counts",
                         lambda: (lambda k: k if "middle" in k["lines"] else None)(
                             c.get("/api/cameras/walker/counts").json()), 10)
    assert counts["lines"]["middle"] == {"in": 0, "out": 0} or sum(
        counts["lines"]["middle"].values()) >= 0
    assert "gate" in counts["lines"]
    assert server.camera("walker")["pid"] == pid        # the same process: no restart


@pytest.mark.slow
def test_live_killed_camera_process_restarts_and_pictures_resume(server):
    before = server.camera("crossing")
    os.kill(before["pid"], signal.SIGKILL)
    after = server.wait("crossing running again in a new process",
                        lambda: (lambda x: x if x["pid"] != before["pid"]
                                 and x["status"] == "running" and x["frames"] > 3 else None)(
        server.camera("crossing")), 40)
    assert after["restarts"] >= 1
    frames = _mjpeg_frames(server.client, "/api/cameras/crossing/stream.mjpg", 2)
    assert len(frames) >= 2
    assert server.camera("walker")["status"] == "running"   # the other camera kept running
    # what the killed process had written of its segment is kept there, under the usual names,
    # with a summary that says how the segment ended
    killed = server.out / "crossing" / before["segment"]
    summary = json.loads((killed / "summary.json").read_text())
    assert summary["status"] == "killed (exit code -9)" and summary["truncated"] is True
    assert (summary["width"], summary["height"], summary["source_fps"]) == (640, 480, 25.0)
    files = {f.name for f in killed.iterdir()}
    assert not [f for f in files if ".part" in f], files
    assert set(summary["outputs"]) <= {"tracks", "events"} and summary["outputs"]
    for name in summary["outputs"]:
        assert (killed / f"{name}.{'txt' if name == 'tracks' else 'jsonl'}").is_file()
    if "tracks" in summary["outputs"]:
        assert len(read_mot(killed / "tracks.txt")) > 0


@pytest.mark.slow
def test_sigterm_stops_cameras_and_commits_their_outputs(tmp_path):
    with _serve(tmp_path, "--rotate-s", "2") as srv:
        srv.wait_running(frames=5, timeout=60)
        srv.wait("a rotated segment", lambda: len(list((srv.out / "walker").iterdir())) >= 2, 20)
        t0 = time.monotonic()
        code = srv.stop()
        took = time.monotonic() - t0
    assert code == 0, srv.logs()
    assert took < 10
    for name in CAMERAS:
        segments = sorted((srv.out / name).iterdir())
        assert len(segments) >= 2 if name == "walker" else len(segments) >= 1
        for seg in segments:
            files = {p.name for p in seg.iterdir()}
            assert {"tracks.txt", "events.jsonl", "summary.json", "counts.csv"} <= files, seg
            assert not [f for f in files if f.endswith(".part") or f.startswith(".")
                        and f != ".motiontrack.lock"], files
            ev = read_events(seg / "events.jsonl")
            assert ev.fps == 25.0
            read_mot(seg / "tracks.txt")
            summary = json.loads((seg / "summary.json").read_text())
            assert summary["frames"] > 0
        last = json.loads((segments[-1] / "summary.json").read_text())
        # the stop ends the segment in progress, unless it came in the frame that rotated it:
        # then that segment ended complete and no next one started
        assert last["interrupted"] is True or (last["status"].startswith("segment rotated")
                                               and not last["interrupted"]), last


@pytest.mark.slow
def test_cameras_stop_and_commit_when_the_server_is_killed(tmp_path):
    with _serve(tmp_path) as srv:
        pids = [c["pid"] for c in srv.wait_running(frames=5, timeout=60).values()]
        srv.proc.kill()
        srv.proc.wait(10)

    def gone(pid: int) -> bool:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        return False

    end = time.monotonic() + 15
    while time.monotonic() < end and not all(gone(p) for p in pids):
        time.sleep(0.2)
    left = [p for p in pids if not gone(p)]
    for p in left:
        os.kill(p, signal.SIGKILL)
    assert not left, "camera processes outlived the server"
    for name in CAMERAS:
        (seg,) = (srv.out / name).iterdir()
        read_events(seg / "events.jsonl")
        assert json.loads((seg / "summary.json").read_text())["interrupted"] is True


@pytest.mark.slow
def test_a_server_and_its_cameras_killed_while_keeping_clips_leave_a_consistent_store(tmp_path):
    """SIGKILL of the server and every camera process at once (the OOM killer, a power cut of
    the process group): each event in the store has its snapshot, and its clip whole or none."""
    from motiontrack.io.clips import read_clip
    from motiontrack.io.event_store import EventStore

    cameras = synth_cameras(tmp_path, {n: f"synth:{n}" for n in CAMERAS})
    for name in CAMERAS:   # short clips, so that one is written within seconds
        scene = tmp_path / name / "scene.toml"
        scene.write_text(scene.read_text() + "\n[evidence]\nclip_s = [1, 1]\n")
    with ServeProcess(tmp_path, cameras) as srv:
        pids = [c["pid"] for c in srv.wait_running(frames=5, timeout=60).values()]

        def a_clip():
            if not (srv.out / "events.db").is_file():
                return None
            with EventStore(srv.out, readonly=True) as store:
                return any(e.clip for e in store)

        srv.wait("a clip recorded in the store", a_clip, 60)
        for pid in (srv.proc.pid, *pids):
            os.kill(pid, signal.SIGKILL)
        srv.proc.wait(10)
    time.sleep(0.5)
    with EventStore(srv.out, readonly=True) as store:
        rows = list(store)
    assert rows and any(e.clip for e in rows)
    for e in rows:
        assert e.snapshot is None or (srv.out / e.snapshot).is_file(), e
        if e.clip is not None:
            frames, fps = read_clip(srv.out / e.clip)
            assert frames and fps > 0, e
