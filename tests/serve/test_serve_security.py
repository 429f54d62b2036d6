"""``motiontrack serve`` and ``track --show`` against hostile pages and clients, and against
hand-edited files.

* DNS rebinding and cross-site writes: the ``Host`` names a server answers to and the
  ``Origin`` of writes (``serve/guard.py``);
* the editor's PUT: a slow scene check leaves the other requests answered, hostile JSON bodies
  (huge integers, deep nesting) get a 400 with a message, a client that leaves mid-upload
  leaves no traceback;
* a scene file edited by hand with a mistake: the camera keeps its last valid scene and keeps
  recording; a bad ``camera =`` calibration is refused before anything starts.

The rules are tested in process (the app over httpx's ASGI transport, the track job's scene
function) and, where they are about HTTP, against real servers on 127.0.0.1: the
``track --show`` page in a thread (:class:`~motiontrack.serve.view.LiveView`), and a
``motiontrack serve`` process with one camera.
"""

from __future__ import annotations

import asyncio
import json
import re
import socket
import threading
import time
from pathlib import Path

import pytest

pytest.importorskip("starlette")
pytest.importorskip("uvicorn")
httpx = pytest.importorskip("httpx")

from motiontrack.cli import main  # noqa: E402
from motiontrack.errors import ConfigError  # noqa: E402
from motiontrack.io.tomlfile import read_toml  # noqa: E402
from motiontrack.serve.app import MAX_BODY, create_app  # noqa: E402
from motiontrack.serve.hosts import LOOPBACK_NAMES, allowed_hosts  # noqa: E402
from motiontrack.serve.hub import Hub  # noqa: E402
from motiontrack.serve.scenes import SceneFiles  # noqa: E402
from helpers.serve_process import ServeProcess  # noqa: E402

LOOPBACK = "http://127.0.0.1:8080"
SCENE = '[[line]]\nname = "gate"\npoints = [[320, 0], [320, 480]]\n'
#: a scene edit the editor would send: the gate and one more line
EDIT = {"lines": [{"name": "gate", "points": [[320, 0], [320, 480]]},
                  {"name": "door", "points": [[0, 240], [640, 240]]}]}


def _app(tmp_path: Path, files=None, **kw):
    """The app over a hub with the camera ``cam`` and its scene file; (app, scene file)."""
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE)
    files = files(scene) if files is not None else {"cam": scene}
    return create_app(Hub([("cam", True)]), scenes=files, **kw), scene


def _requests(app, *calls):
    """Send ``(method, url, kwargs)`` requests to ``app`` in order, on one event loop; their
    responses."""
    async def go():
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url=LOOPBACK) as c:
            return [await c.request(m, url, **kw) for m, url, kw in calls]

    return asyncio.run(go())


# ---------------------------------------------------------------------- host names, origins
@pytest.mark.parametrize("bind, extra, hosts", [
    ("127.0.0.1", (), LOOPBACK_NAMES),
    ("::1", (), LOOPBACK_NAMES),
    ("localhost", (), LOOPBACK_NAMES),
    ("127.0.0.2", (), LOOPBACK_NAMES | {"127.0.0.2"}),
    ("127.0.0.1", ("Cams.LAN", "[FE80::1]", "10.0.0.7"),
     LOOPBACK_NAMES | {"cams.lan", "fe80::1", "10.0.0.7"}),
    ("192.168.1.5", (), {"192.168.1.5"}),                  # not reachable as localhost
    ("0.0.0.0", (), None),                                  # any: a token guards it
    ("::", (), None),
    ("0.0.0.0", ("cams.lan",), LOOPBACK_NAMES | {"cams.lan"}),
])
def test_a_server_answers_to_the_names_of_its_address(bind, extra, hosts):
    assert allowed_hosts(bind, extra) == (frozenset(hosts) if hosts is not None else None)


@pytest.mark.parametrize("name", ["cams.lan:8080", "http://cams.lan", "cams.lan/x", "", "[::1",
                                  "a b", "[::1]:80", "fe80::zz"])
def test_an_allowed_host_with_a_port_scheme_or_path_is_refused(name):
    with pytest.raises(ConfigError, match=r"--allowed-host must be a host name or an IP address"):
        allowed_hosts("127.0.0.1", [name])


@pytest.mark.parametrize("host, status", [
    ("127.0.0.1:8080", 200), ("127.0.0.1", 200), ("localhost:8080", 200), ("LocalHost", 200),
    ("[::1]:8080", 200), ("[::1]", 200), ("[0:0:0:0:0:0:0:1]:8080", 200),
    ("cams.lan:8080", 200),                                  # given with --allowed-host
    ("evil.example:8080", 403), ("evil.example", 403), ("127.0.0.1.evil.example", 403),
    ("localhost.evil.example:8080", 403), ("evil.example@127.0.0.1", 403), ("[::1", 403),
    ("127.0.0.1:8080:80", 403), ("::1", 403), ("", 403), ("cams.lan.:8080", 403),
])
def test_a_request_naming_another_host_is_refused(tmp_path, host, status):
    app, _ = _app(tmp_path, hosts=allowed_hosts("127.0.0.1", ["cams.lan"]))
    (r,) = _requests(app, ("GET", "/api/cameras", {"headers": {"Host": host}}))
    assert r.status_code == status, r.text
    if status == 403:
        assert "--allowed-host" in r.json()["error"]


def test_a_rebound_page_can_neither_read_nor_write(tmp_path):
    """What a page of evil.example sends once its name resolves to 127.0.0.1: its own name as
    Host, on every route, with or without the token."""
    app, scene = _app(tmp_path, hosts=LOOPBACK_NAMES, token="t0k")
    evil = {"Host": "evil.example:8080", "Authorization": "Bearer t0k"}
    rs = _requests(app, *[("GET", route, {"headers": evil}) for route in (
        "/", "/static/app.js", "/api/cameras", "/api/cameras/cam/scene",
        "/api/cameras/cam/snapshot.jpg", "/api/cameras/cam/stream.mjpg", "/api/events")],
        ("PUT", "/api/cameras/cam/scene", {"headers": evil, "json": EDIT}))
    assert [r.status_code for r in rs] == [403] * len(rs)
    assert scene.read_text() == SCENE


@pytest.mark.parametrize("origin, status", [
    (None, 200),                                  # curl, a script: no Origin
    ("http://127.0.0.1:8080", 200),               # the page itself
    ("http://evil.example", 403), ("https://evil.example:8080", 403),
    ("http://127.0.0.1:9999", 403),               # another server on this machine
    ("http://localhost:8080", 403),               # another origin, even if the same machine
    ("null", 403), ("", 403), ("file://", 403), ("http://127.0.0.1:8080/x", 403),
])
def test_a_write_from_another_sites_page_is_refused(tmp_path, origin, status):
    app, scene = _app(tmp_path)
    headers = {"Origin": origin} if origin is not None else {}
    (r, read) = _requests(app, ("PUT", "/api/cameras/cam/scene", {"json": EDIT,
                                                                "headers": headers}),
                          ("GET", "/api/cameras", {"headers": headers}))
    assert r.status_code == status, r.text
    assert read.status_code == 200                 # reads: a browser keeps them from the page
    names = [ln["name"] for ln in read_toml(scene)["line"]]
    assert names == (["gate", "door"] if status == 200 else ["gate"])
    if status == 403:
        assert "Origin" in r.json()["error"]


def test_a_page_behind_a_proxy_with_the_default_port_is_its_own_origin(tmp_path):
    app, _ = _app(tmp_path, hosts=allowed_hosts("127.0.0.1", ["cams.example.com"]))
    for origin, host in (("https://cams.example.com", "cams.example.com"),
                         ("https://cams.example.com", "cams.example.com:443"),
                         ("http://[::1]:8080", "[::1]:8080")):
        (r,) = _requests(app, ("PUT", "/api/cameras/cam/scene",
                               {"json": EDIT, "headers": {"Origin": origin, "Host": host}}))
        assert r.status_code == 200, (origin, host, r.text)


# ------------------------------------------------------------------------ the editor's PUT
def test_a_slow_scene_check_leaves_other_requests_answered(tmp_path):
    """The scene check runs off the event loop: while one takes long (here it waits for the
    test), the API and the streams keep answering."""
    started, release = threading.Event(), threading.Event()

    class SlowCheck(SceneFiles):
        def write(self, name, payload, size=None):
            started.set()
            release.wait(3)            # a long check (a scene of thousands of points)
            return super().write(name, payload, size)

    app, scene = _app(tmp_path, files=lambda s: SlowCheck({"cam": s}))

    async def go():
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url=LOOPBACK) as c:
            put = asyncio.create_task(c.put("/api/cameras/cam/scene", json=EDIT))
            for _ in range(200):
                if started.is_set():
                    break
                await asyncio.sleep(0.01)
            t0 = time.monotonic()
            other = await c.get("/api/cameras")
            answered = time.monotonic() - t0
            still_checking = not put.done()
            release.set()
            return other, answered, still_checking, await put

    other, answered, still_checking, put = asyncio.run(go())
    assert started.is_set() and other.status_code == 200
    assert still_checking and answered < 1.0, answered
    assert put.status_code == 200
    assert [ln["name"] for ln in read_toml(scene)["line"]] == ["gate", "door"]


def _points(n: int) -> str:
    return ", ".join(f"[{i}, {i}]" for i in range(n))


@pytest.mark.parametrize("body, message", [
    # 400 digits: more than a float holds
    ('{"lines": [{"name": "x", "points": [[0, 0], [%s, 1]]}]}' % ("1" * 400),
     "the body holds an integer of 400 digits; integers must be within +-9223372036854775807"),
    ('{"zones": [{"name": "z", "polygon": [[0, 0], [9, 0], [9, 9]], "loiter_s": -%s}]}'
     % ("9" * 30), "the body holds an integer of 30 digits"),
    ('{"lines": [{"name": "x", "points": [[0, 0], [%s, 1]]}]}' % ("1" * 5000),
     "numbers of at most 19 digits"),                       # over Python's own 4300
    ('{"lines": ' + "[" * 30_000 + "]" * 30_000 + "}", "nested deeper than 16 levels"),
    ('{"lines": [{"name": "x", "points": [[0, 0], [1, 1]], "w": %s}]}'
     % ("[" * 900 + "]" * 900), "nested deeper than 16 levels"),
    ('{"lines": [', "the body must be a JSON object: Expecting value at line 1 column 12"),
])
def test_a_hostile_scene_body_gets_a_message_not_a_500(tmp_path, body, message):
    app, scene = _app(tmp_path)
    assert len(body) <= MAX_BODY
    (r,) = _requests(app, ("PUT", "/api/cameras/cam/scene", {"content": body.encode()}))
    assert r.status_code == 400, r.text
    assert message in r.json()["error"]
    assert scene.read_text() == SCENE


def test_a_scene_file_that_cannot_be_read_is_a_conflict_with_its_message(tmp_path):
    app, scene = _app(tmp_path)
    scene.write_text("[[line]\n")                     # edited by hand: not TOML
    (got, put) = _requests(app, ("GET", "/api/cameras/cam/scene", {}),
                           ("PUT", "/api/cameras/cam/scene", {"json": EDIT}))
    assert got.status_code == 409 and "malformed scene file" in got.json()["error"]
    assert put.status_code == 400 and "malformed scene file" in put.json()["error"]
    assert scene.read_text() == "[[line]\n"


def test_a_body_not_in_utf8_gets_a_message(tmp_path):
    app, _ = _app(tmp_path)
    (r,) = _requests(app, ("PUT", "/api/cameras/cam/scene", {"content": b'{"lines": "\xff"}'}))
    assert r.status_code == 400 and "UTF-8" in r.json()["error"]


# ------------------------------------------------------------------- track --show's page
def test_the_show_page_answers_only_to_its_own_host_names():
    """The live page of ``track --show`` is a real server on 127.0.0.1 in a thread."""
    from motiontrack.serve.view import LiveView

    view = LiveView("cam", allowed=["cams.lan"])
    try:
        with httpx.Client(base_url=view.url, timeout=5) as c:
            for host, status in (("evil.example:%d", 403), ("127.0.0.1:%d", 200),
                                 ("localhost:%d", 200), ("[::1]:%d", 200), ("cams.lan:%d", 200),
                                 ("cams.lan.evil.example:%d", 403)):
                r = c.get("/api/cameras", headers={"Host": host % view.port})
                assert r.status_code == status, (host, r.text)
            assert c.get("/", headers={"Host": "evil.example"}).status_code == 403
    finally:
        view.close()
    with pytest.raises(ConfigError, match="--allowed-host"):
        LiveView("cam", allowed=["cams.lan:80"])


def test_the_show_page_accepts_connections_as_soon_as_its_address_is_printed(monkeypatch):
    """The address is printed when LiveView returns; a browser opened at once must reach it
    even while the server thread is still starting."""
    import socket
    import threading

    import uvicorn

    from motiontrack.serve.view import LiveView

    go = threading.Event()
    run = uvicorn.Server.run

    def late_run(self, *args, **kwargs):
        go.wait(10)
        return run(self, *args, **kwargs)

    monkeypatch.setattr(uvicorn.Server, "run", late_run)
    view = LiveView("cam")
    try:
        with socket.create_connection(("127.0.0.1", view.port), timeout=5) as sock:
            go.set()
            sock.sendall(b"GET /api/cameras HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                         b"Connection: close\r\n\r\n")
            assert sock.recv(64).startswith(b"HTTP/1.1 200")
    finally:
        go.set()
        view.close()


# ------------------------------------------------------------------------ the cameras file
@pytest.mark.parametrize("calibration, message", [
    ("missing.xml", r"^motiontrack: error: camera\[1\] \(gate\): camera = missing.xml: camera "
                    r"file not found: .*missing.xml$"),
    ("bad.xml", r"^motiontrack: error: camera\[1\] \(gate\): camera = bad.xml: malformed Tsai "
                r"camera XML .*bad.xml: syntax error: line 1, column 0$"),
])
def test_a_bad_calibration_in_the_cameras_file_is_refused_before_anything_starts(
        tmp_path, capsys, monkeypatch, calibration, message):
    monkeypatch.delenv("MOTIONTRACK_TOKEN", raising=False)
    (tmp_path / "bad.xml").write_text("not xml <<<")
    cams = tmp_path / "cameras.toml"
    cams.write_text(f'[[camera]]\nname = "gate"\nsource = "synth:walker"\n'
                    f'camera = "{calibration}"\n')
    out = tmp_path / "out"
    with socket.socket() as busy:   # a port in use: a server that got further would stop there
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = str(busy.getsockname()[1])
        assert main(["serve", str(cams), "--port", port, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert re.match(message, err), err
    assert len(err.splitlines()) == 1 and not out.exists()


def test_serve_refuses_an_allowed_host_with_a_port(tmp_path, capsys):
    cams = tmp_path / "cameras.toml"
    cams.write_text('[[camera]]\nname = "gate"\nsource = "synth:walker"\n')
    with socket.socket() as busy:   # a port in use: a server that got further would stop there
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = str(busy.getsockname()[1])
        assert main(["serve", str(cams), "--port", port, "--allowed-host", "cams.lan:8080"]) == 2
    err = capsys.readouterr().err
    assert "--allowed-host must be a host name" in err and "Traceback" not in err


# ------------------------------------------------------------- a scene file edited by hand
def test_a_bad_scene_file_keeps_the_last_valid_scene_until_it_is_valid_again(tmp_path, caplog):
    from motiontrack.serve.worker import SceneKeeper

    path = tmp_path / "scene.toml"
    path.write_text(SCENE)
    keeper = SceneKeeper("gate", path)
    first = keeper.load(None)
    assert [ln.name for ln in first.lines] == ["gate"] and keeper.error is None
    for bad in ('[[line]]\nname = "gate"\npoints = [[320, 0]]\n',      # one point
                '[[line]\nname = "gate"\n'):                            # not TOML
        path.write_text(bad)
        with caplog.at_level("ERROR", logger="motiontrack.serve.worker"):
            caplog.clear()
            assert keeper.load(None) is first and keeper.load(None) is first
        assert keeper.error.endswith("the camera keeps its last valid scene until the file is "
                                     "valid")
        assert "scene file" in keeper.error
        assert len(caplog.records) == 1            # once per problem, not once per segment
    path.unlink()
    assert keeper.load(None) is first and "not found" in keeper.error
    path.write_text(SCENE.replace("gate", "door"))
    again = keeper.load(None)
    assert [ln.name for ln in again.lines] == ["door"] and keeper.error is None
    # a camera process started while the file is bad has no scene to keep
    path.write_text("[[line]]\n")
    fresh = SceneKeeper("gate", path)
    assert fresh.load(None) is None
    assert fresh.error.endswith("the camera runs without lines and zones until the file is valid")


# --------------------------------------------------------------------------- a live server
@pytest.fixture(scope="module")
def served(tmp_path_factory):
    """``motiontrack serve`` with the looping camera ``c`` (synth:walker at 10 fps, segments
    of 1 s) and its scene file, answering to ``cams.lan`` too."""
    root = tmp_path_factory.mktemp("security")
    (root / "scene.toml").write_text(SCENE)
    cameras = {"c": {"source": "synth:walker", "scene": "scene.toml", "loop": True, "fps": 10}}
    with ServeProcess(root, cameras, "--allowed-host", "cams.lan", "--rotate-s", "1") as srv:
        srv.wait_running(frames=2, timeout=60)
        yield srv


def _log(srv: ServeProcess) -> str:
    return (srv.root / "serve.log").read_text(errors="replace")


@pytest.mark.slow
def test_live_a_rebound_name_is_refused_and_the_scene_is_not_rewritten(served):
    """``curl -X PUT -H 'Host: evil.example:PORT' --data '{"lines": ...}' .../scene``."""
    c, port, scene = served.client, served.port, served.root / "scene.toml"
    r = c.put("/api/cameras/c/scene", json=EDIT, headers={"Host": f"evil.example:{port}"})
    assert r.status_code == 403 and "--allowed-host" in r.json()["error"]
    for route in ("/api/cameras", "/api/cameras/c/snapshot.jpg", "/"):
        assert c.get(route, headers={"Host": f"evil.example:{port}"}).status_code == 403
    r = c.put("/api/cameras/c/scene", json=EDIT,
              headers={"Origin": "http://evil.example", "Host": f"localhost:{port}"})
    assert r.status_code == 403 and "Origin" in r.json()["error"]
    assert scene.read_text() == SCENE
    for host in (f"localhost:{port}", f"[::1]:{port}", f"cams.lan:{port}", "127.0.0.1"):
        assert c.get("/api/cameras", headers={"Host": host}).status_code == 200, host


@pytest.mark.slow
def test_live_an_oversized_body_is_refused_before_it_is_sent(served):
    with socket.create_connection(("127.0.0.1", served.port), timeout=5) as s:
        s.sendall(f"PUT /api/cameras/c/scene HTTP/1.1\r\nHost: 127.0.0.1:{served.port}\r\n"
                  f"Content-Type: application/json\r\nContent-Length: 100000000\r\n\r\n{{"
                  .encode())
        assert s.recv(4096).startswith(b"HTTP/1.1 413 ")   # without the other 99.99 MB


@pytest.mark.slow
def test_live_a_client_leaving_mid_upload_leaves_no_traceback(served):
    for _ in range(2):
        with socket.create_connection(("127.0.0.1", served.port), timeout=5) as s:
            s.sendall(f"PUT /api/cameras/c/scene HTTP/1.1\r\nHost: 127.0.0.1:{served.port}\r\n"
                      f"Content-Type: application/json\r\nContent-Length: 5000\r\n\r\n"
                      f'{{"lines": ['.encode())
            time.sleep(0.2)                        # the app waits for the rest of the body
    assert served.camera("c")["status"] == "running"   # the server answers and goes on
    time.sleep(0.3)
    log = _log(served)
    assert "Traceback" not in log and "Exception" not in log, served.logs()


@pytest.mark.slow
def test_live_a_bad_hand_edit_of_the_scene_keeps_the_camera_recording(served):
    c, scene = served.client, served.root / "scene.toml"
    before = served.camera("c")
    assert before["scene_error"] is None
    scene.write_text('[[line]]\nname = "gate"\npoints = [[320, 0]]\n')    # one point
    cam = served.wait("the scene file's problem in the camera's status",
                      lambda: (lambda x: x if x["scene_error"] else None)(served.camera("c")), 20)
    assert "scene file scene.toml: line[1].points" in cam["scene_error"]
    assert "keeps its last valid scene" in cam["scene_error"]
    # segments go on (one a second) with the last valid scene, in the same process
    served.wait("two more segments", lambda: served.camera("c")["segment"] != cam["segment"]
                and served.camera("c")["frames"] > cam["frames"] + 10, 20)
    now = served.camera("c")
    assert (now["status"], now["pid"], now["restarts"]) == ("running", before["pid"], 0)
    assert now["scene_error"] == cam["scene_error"]
    assert list(c.get("/api/cameras/c/counts").json()["lines"]) == ["gate"]
    assert _log(served).count("line[1].points") == 1          # said once, not per segment
    segment = served.out / "c" / now["segment"]
    scene.write_text(SCENE + '[[line]]\nname = "door"\npoints = [[0, 240], [640, 240]]\n')
    served.wait("the valid file applied", lambda: served.camera("c")["scene_error"] is None
                and "door" in c.get("/api/cameras/c/counts").json()["lines"], 20)
    assert served.camera("c")["pid"] == before["pid"]
    # the segments run with the kept scene recorded their events with it
    served.wait("a segment with the kept scene committed",
                lambda: (segment / "summary.json").is_file(), 10)
    header = json.loads((segment / "events.jsonl").read_text().splitlines()[0])
    assert header["scene"].endswith("scene.toml")
