"""Event sinks: webhook (HTTP POST per event) and MQTT (QoS 1) beside events.jsonl.

Real receivers on 127.0.0.1: a ``http.server`` in a thread, and Debian's ``mosquitto`` broker
started by a fixture on a free port (skipped when absent, failing under
MOTIONTRACK_REQUIRE_DATA=1, as the real data does).
"""

from __future__ import annotations

import contextlib
import http.server
import json
import os
import shutil
import socket
import subprocess
import threading
import time
from pathlib import Path

import pytest

from helpers import free_port
from motiontrack.cli import main
from motiontrack.errors import ConfigError
from motiontrack.io.mot import write_mot
from motiontrack.io.sinks import (BACKOFF_S, FLUSH_S, MqttDelivery, MqttTarget, WebhookDelivery,
                                  WebhookTarget, encode, parse_mqtt, parse_webhook)
from motiontrack.synth import make_scene


def _required(what: str) -> None:
    """Skip for a missing service, or fail under MOTIONTRACK_REQUIRE_DATA=1 (.ci/run)."""
    if os.environ.get("MOTIONTRACK_REQUIRE_DATA") == "1":
        pytest.fail(f"{what} and MOTIONTRACK_REQUIRE_DATA=1")
    pytest.skip(what)


# ------------------------------------------------------------------------------ receivers
class _Receiver(http.server.BaseHTTPRequestHandler):
    """Answers each POST with the next status of ``server.statuses`` (200 once they run out)
    and keeps the JSON bodies it answered 2xx."""

    def do_POST(self):  # noqa: N802 (http.server's name)
        body = self.rfile.read(int(self.headers["Content-Length"]))
        srv = self.server
        with srv.lock:
            status = srv.statuses.pop(0) if srv.statuses else 200
            srv.requests.append((self.path, self.headers.get("Authorization"), status))
            if 200 <= status < 300:
                srv.bodies.append(json.loads(body))
        self.send_response(status)
        self.send_header("Content-Length", "0")
        self.end_headers()

    def log_message(self, *args):
        pass


@contextlib.contextmanager
def http_receiver(statuses=()):
    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _Receiver)
    srv.daemon_threads = True
    srv.lock, srv.statuses, srv.requests, srv.bodies = threading.Lock(), list(statuses), [], []
    t = threading.Thread(target=srv.serve_forever, daemon=True)
    t.start()
    try:
        yield srv, f"http://127.0.0.1:{srv.server_address[1]}/events"
    finally:
        srv.shutdown()
        srv.server_close()
        t.join(5)


@contextlib.contextmanager
def silent_receiver():
    """Accepts connections (the kernel's backlog) and never answers."""
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(64)
    try:
        yield f"http://127.0.0.1:{s.getsockname()[1]}/events"
    finally:
        s.close()


def _mosquitto() -> str | None:
    # Debian installs it in /usr/sbin, which is not on every user's PATH
    return shutil.which("mosquitto") or shutil.which("mosquitto", path="/usr/sbin:/sbin")


def _start_broker(conf: Path, port: int, log: Path) -> subprocess.Popen:
    with log.open("ab") as out:   # the broker keeps its own copy of the descriptor
        proc = subprocess.Popen([_mosquitto(), "-c", str(conf)],
                                stdout=out, stderr=subprocess.STDOUT)
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 0.2):
            return proc
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    proc.kill()
    proc.wait()
    pytest.fail(f"mosquitto did not listen on 127.0.0.1:{port}: {log.read_text()[-500:]}")


class Broker:
    def __init__(self, folder: Path) -> None:
        self.port = free_port()
        self.conf = folder / "mosquitto.conf"
        self.conf.write_text(f"listener {self.port} 127.0.0.1\nallow_anonymous true\n")
        self.log = folder / "mosquitto.log"
        self.proc = _start_broker(self.conf, self.port, self.log)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            self.proc.wait(10)

    def restart(self) -> None:
        self.stop()
        self.proc = _start_broker(self.conf, self.port, self.log)


@pytest.fixture
def broker(tmp_path):
    """A mosquitto broker of its own on a free 127.0.0.1 port."""
    if _mosquitto() is None:
        _required("mosquitto not found (apt-get install mosquitto)")
    b = Broker(tmp_path)
    yield b
    b.stop()


@pytest.fixture
def paho():
    try:
        import paho.mqtt.client as mqtt
    except ImportError:
        _required("paho-mqtt not installed (pip install 'motiontrack[mqtt]')")
    return mqtt


@contextlib.contextmanager
def subscriber(mqtt, port: int, topic: str):
    """A paho client subscribed (QoS 1) to ``topic``; yields the list of decoded payloads."""
    got, ready = [], threading.Event()
    c = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="motiontrack-test-subscriber")
    c.on_connect = lambda cl, u, f, rc, p: cl.subscribe(topic, qos=1)
    c.on_subscribe = lambda cl, u, mid, rcs, p: ready.set()
    c.on_message = lambda cl, u, msg: got.append((msg.topic, json.loads(msg.payload)))
    c.connect("127.0.0.1", port)
    c.loop_start()
    try:
        assert ready.wait(10), "the subscription was not acknowledged"
        yield got
    finally:
        c.disconnect()
        c.loop_stop()


def _wait_for(cond, seconds: float = 10.0) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if cond():
            return True
        time.sleep(0.02)
    return cond()


# ------------------------------------------------------------------------------- helpers
def _events_of(run: Path) -> list[dict]:
    lines = (run / "events.jsonl").read_text().splitlines()
    return [json.loads(x) for x in lines[1:]]


def _without_camera(bodies, camera: str) -> list[dict]:
    assert all(b["camera"] == camera for b in bodies)
    return [{k: v for k, v in b.items() if k != "camera"} for b in bodies]


@pytest.fixture(scope="module")
def walker(tmp_path_factory):
    """The walker scene's scene file and its exact ground-truth tracks (a MOTChallenge file in
    a folder named ``lobby``): ``analyze`` finds a zone entry, a line crossing and a zone exit."""
    folder = tmp_path_factory.mktemp("lobby") / "lobby"
    folder.mkdir()
    s = make_scene("walker")
    scene = folder / "walker.toml"
    scene.write_text(s.scene_toml())
    tracks = folder / "gt.txt"
    write_mot(s.ground_truth(), tracks)
    return scene, tracks


def _analyze(walker, out: Path, *extra: str) -> int:
    scene, tracks = walker
    return main(["analyze", str(tracks), "--scene", str(scene), "--fps", "25", "-o", str(out),
                 *extra])


# ------------------------------------------------------------------------------- parsing
@pytest.mark.parametrize("url, target", [
    ("http://127.0.0.1:8080/hook", WebhookTarget("http://127.0.0.1:8080/hook")),
    ("HTTPS://example.org/a?b=1", WebhookTarget("https://example.org/a?b=1")),
    # credentials become a Basic header ("u:p" base64) and leave the URL (summaries, logs)
    ("https://u:p@example.org/h", WebhookTarget("https://example.org/h", "Basic dTpw")),
])
def test_webhook_urls(url, target):
    assert parse_webhook(url) == target


@pytest.mark.parametrize("url, target", [
    ("mqtt://broker", MqttTarget("broker", 1883, "motiontrack")),
    ("mqtt://broker:1884/site/a", MqttTarget("broker", 1884, "site/a")),
    ("mqtts://me:pw@broker/", MqttTarget("broker", 8883, "motiontrack", True, "me", "pw")),
])
def test_mqtt_urls(url, target):
    assert parse_mqtt(url) == target
    assert target.topic("door") == f"{target.prefix}/door/events"
    assert "pw" not in target.describe()


@pytest.mark.parametrize("parse, url, message", [
    (parse_webhook, "ftp://x/y", "--webhook needs a http:// or https:// URL"),
    (parse_webhook, "http:///path", "names no host"),
    (parse_webhook, "http://h:99999/", "the port must be a number in [1, 65535]"),
    (parse_webhook, "http://h/a b", "no spaces"),
    (parse_webhook, "http://u:secret@h/#x", "fragment"),
    (parse_mqtt, "tcp://h", "--mqtt needs a mqtt:// or mqtts:// URL"),
    (parse_mqtt, "mqtt://h/a/#", "may not hold '+', '#'"),
    (parse_mqtt, "mqtt://h/a/+", "may not hold '+', '#'"),
    (parse_mqtt, "mqtt://h?x=1", "query"),
])
def test_bad_sink_urls_name_the_problem(parse, url, message):
    with pytest.raises(ConfigError, match=None) as err:
        parse(url)
    assert message in str(err.value) and "secret" not in str(err.value)


@pytest.mark.parametrize("args, message", [
    (["--webhook", "ftp://x"], "--webhook needs a http:// or https:// URL"),
    (["--mqtt", "mqtt://h:0"], "the port must be a number"),
    (["--webhook", "http://h/", "--camera-name", "a/b"], "--camera-name must be"),
    (["--webhook", "http://h/", "--sink-queue", "0"], "--sink-queue must be at least 1, got 0"),
    (["--webhook", "http://h/", "--sink-timeout", "0"], "--sink-timeout must be seconds > 0"),
    (["--webhook", "http://h/", "--sink-timeout", "nan"], "--sink-timeout must be seconds > 0"),
    (["--webhook", "http://h/", "--sink-retries", "-1"], "--sink-retries must be 0 or more"),
    (["--webhook", "http://h/", "--sink-wait", "-2"], "--sink-wait must be seconds >= 0"),
])
def test_bad_sink_option_is_one_line_and_exit_2_before_the_run(tmp_path, walker, capsys, args,
                                                             message):
    out = tmp_path / "out"
    assert _analyze(walker, out, *args) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not out.exists()
    # track checks them before the source opens, and needs --scene for them
    assert main(["track", "synth:walker", "-o", str(out), "--scene", str(walker[0]), *args]) == 2
    assert message in capsys.readouterr().err and not out.exists()


def test_the_sink_options_default_to_the_sinks_own_settings():
    from motiontrack.cli import build_parser
    from motiontrack.cli._sinks import sink_settings
    from motiontrack.io.sinks import SinkSettings

    for command in (["track", "x.mp4"], ["analyze", "t.txt", "--scene", "s.toml", "-o", "o"]):
        args = build_parser().parse_args([*command, "--webhook", "http://h/"])
        assert sink_settings(args) == SinkSettings()
    assert SinkSettings().flush_s == FLUSH_S   # a run waits FLUSH_S for its sinks by default


def test_sink_settings_reach_every_delivery():
    from motiontrack.io.sinks import SinkSettings, parse_mqtt, parse_webhook
    from motiontrack.run.event_sinks import deliveries

    hook, mqtt = parse_webhook("http://127.0.0.1:9/e"), parse_mqtt("mqtt://127.0.0.1:9")
    st = SinkSettings(queue_size=3, timeout_s=1.5, retries=2, flush_s=0.5)
    try:
        webhook, broker = deliveries([hook, mqtt], "cam", st)
    except ConfigError:   # paho-mqtt missing: the webhook alone
        (webhook,), broker = deliveries([hook], "cam", st), None
    try:
        assert (webhook.timeout_s, webhook.max_retries, webhook._queue.maxsize) == (1.5, 2, 3)
        if broker is not None:
            assert broker._queue.maxsize == 3
    finally:
        for d in (webhook, broker):
            if d is not None:
                d.close(deadline=time.monotonic())


def test_track_sinks_need_a_scene(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["track", "synth:walker", "-o", str(out), "--webhook", "http://h/"]) == 2
    assert "give --scene" in capsys.readouterr().err and not out.exists()


# ------------------------------------------------------------------------------- webhook
@pytest.mark.slow
def test_track_scene_posts_every_event_of_events_jsonl_to_the_webhook(tmp_path, walker):
    scene, _ = walker
    run = tmp_path / "run"
    with http_receiver() as (srv, url):
        assert main(["track", "synth:walker", "--scene", str(scene), "--no-video", "-o", str(run),
                     "--webhook", url]) == 0
    events = _events_of(run)
    assert len(events) >= 3   # the walker enters the plaza, crosses the gate, leaves
    # the same objects in the same order, each with the camera's name (the source's by default)
    assert _without_camera(srv.bodies, "synth-walker") == events
    sinks = json.loads((run / "summary.json").read_text())["sinks"]
    assert sinks == [{"sink": "webhook", "target": url, "events": len(events),
                      "delivered": len(events), "failed": 0, "dropped": 0, "retries": 0}]


def test_analyze_posts_its_events_with_basic_auth_and_the_camera_name(tmp_path, walker):
    out = tmp_path / "out"
    with http_receiver() as (srv, url):
        hook = url.replace("http://", "http://cam:s3cret@")
        assert _analyze(walker, out, "--webhook", hook, "--camera-name", "door-1") == 0
    events = _events_of(out)
    assert [e["type"] for e in events] == ["zone_enter", "line_cross", "zone_exit"]
    assert _without_camera(srv.bodies, "door-1") == events
    assert {(p, a) for p, a, _ in srv.requests} == {("/events", "Basic Y2FtOnMzY3JldA==")}
    summary = (out / "summary.json").read_text()
    assert "s3cret" not in summary and json.loads(summary)["sinks"][0]["delivered"] == 3


def test_analyze_default_camera_name_is_the_tracks_folder(tmp_path, walker):
    with http_receiver() as (srv, url):
        assert _analyze(walker, tmp_path / "out", "--webhook", url) == 0
    assert {b["camera"] for b in srv.bodies} == {"lobby"}


def test_webhook_retries_a_server_error_then_delivers_in_order():
    waits: list[float] = []   # the back-off, driven without waiting it out
    with http_receiver(statuses=[500, 503]) as (srv, url):
        d = WebhookDelivery(parse_webhook(url), sleep=waits.append)
        d.start()
        for k in range(3):
            assert d.offer(encode({"n": k}))
        stats = d.close(time.monotonic() + 30)
    # the first event was answered 500, then 503, then 200: two retries, nothing lost, in order
    assert [s for _, _, s in srv.requests] == [500, 503, 200, 200, 200]
    assert srv.bodies == [{"n": 0}, {"n": 1}, {"n": 2}]
    assert waits == [BACKOFF_S, 2 * BACKOFF_S]   # exponential back-off before each retry
    assert (stats["delivered"], stats["retries"], stats["dropped"], stats["failed"]) == (3, 2, 0, 0)


def test_webhook_client_error_fails_the_event_without_retrying(tmp_path, walker):
    out = tmp_path / "out"
    with http_receiver(statuses=[404]) as (srv, url):
        assert _analyze(walker, out, "--webhook", url) == 0
    assert [s for _, _, s in srv.requests] == [404, 200, 200]
    sink = json.loads((out / "summary.json").read_text())["sinks"][0]
    assert (sink["delivered"], sink["failed"], sink["retries"]) == (2, 1, 0)


def test_webhook_that_never_answers_does_not_stall_the_run(tmp_path, walker):
    out = tmp_path / "out"
    wait = 1.5   # FLUSH_S without --sink-wait (test_the_sink_options_default_to_...)
    with silent_receiver() as url:
        t0 = time.monotonic()
        assert _analyze(walker, out, "--webhook", url, "--sink-wait", str(wait)) == 0
        elapsed = time.monotonic() - t0
    # the run waits --sink-wait for the sink at its end, then counts what it holds as dropped
    # (unbounded, it would wait for 6 attempts of 5 s and their back-off per event)
    assert wait - 0.5 < elapsed < wait + 6.0
    sink = json.loads((out / "summary.json").read_text())["sinks"][0]
    assert (sink["events"], sink["delivered"], sink["dropped"]) == (3, 0, 3)
    assert len(_events_of(out)) == 3
    # --sink-wait shortens the wait at the end
    t0 = time.monotonic()
    with silent_receiver() as url:
        assert _analyze(walker, tmp_path / "short", "--webhook", url, "--sink-wait", "0.5",
                        "--sink-timeout", "0.2") == 0
    assert time.monotonic() - t0 < FLUSH_S - 1.0


def test_full_queue_drops_instead_of_blocking_and_counts_add_up():
    with silent_receiver() as url:
        d = WebhookDelivery(parse_webhook(url), queue_size=2, timeout_s=30)
        d.start()
        t0 = time.monotonic()
        accepted = [d.offer(encode({"n": k})) for k in range(10)]
        offering = time.monotonic() - t0
        stats = d.close(time.monotonic() + 0.2)
    assert offering < 0.5   # never waits for the receiver
    # the thread took at most one event off the queue, the queue holds two: >= 7 refused
    assert accepted.count(False) >= 7
    assert (stats["events"], stats["delivered"], stats["failed"], stats["dropped"]) == (10, 0, 0, 10)


def test_close_during_back_off_returns_at_the_deadline():
    down = f"http://127.0.0.1:{free_port()}/events"   # nothing listens: connection refused
    d = WebhookDelivery(parse_webhook(down), backoff_s=10)
    d.start()
    d.offer(encode({"n": 1}))
    # the first attempt fails, the back-off of 10 s starts
    assert _wait_for(lambda: d.stats()["retries"] == 1)
    t0 = time.monotonic()
    stats = d.close(time.monotonic() + 0.3)
    assert time.monotonic() - t0 < 1.0
    assert (stats["dropped"], stats["retries"]) == (1, 1)


# ---------------------------------------------------------------------------------- MQTT
def test_analyze_publishes_every_event_to_mqtt_with_qos_1(tmp_path, walker, broker, paho):
    out = tmp_path / "out"
    with subscriber(paho, broker.port, "site/+/events") as got:
        assert _analyze(walker, out, "--mqtt", f"mqtt://127.0.0.1:{broker.port}/site") == 0
        events = _events_of(out)
        assert _wait_for(lambda: len(got) >= len(events))
    assert {t for t, _ in got} == {"site/lobby/events"}
    assert _without_camera([b for _, b in got], "lobby") == events
    sink = json.loads((out / "summary.json").read_text())["sinks"][0]
    assert sink == {"sink": "mqtt", "target": f"mqtt://127.0.0.1:{broker.port}/site",
                    "events": 3, "delivered": 3, "failed": 0, "dropped": 0, "retries": 0,
                    "topic": "site/lobby/events", "reconnects": 0}


@pytest.mark.slow
def test_track_scene_sends_the_same_events_to_mqtt_and_webhook(tmp_path, walker, broker, paho):
    scene, _ = walker
    run = tmp_path / "run"
    with subscriber(paho, broker.port, "motiontrack/#") as got, http_receiver() as (srv, url):
        assert main(["track", "synth:walker", "--scene", str(scene), "--no-video", "-o", str(run),
                     "--mqtt", f"mqtt://127.0.0.1:{broker.port}", "--webhook", url,
                     "--camera-name", "walkway"]) == 0
        events = _events_of(run)
        assert _wait_for(lambda: len(got) >= len(events))
    assert {t for t, _ in got} == {"motiontrack/walkway/events"}
    assert _without_camera([b for _, b in got], "walkway") == events
    assert _without_camera(srv.bodies, "walkway") == events
    sinks = json.loads((run / "summary.json").read_text())["sinks"]
    assert [(s["sink"], s["delivered"], s["dropped"]) for s in sinks] == [
        ("webhook", len(events), 0), ("mqtt", len(events), 0)]


def test_mqtt_delivers_what_was_queued_while_the_broker_restarted(broker, paho):
    d = MqttDelivery(parse_mqtt(f"mqtt://127.0.0.1:{broker.port}"), "cam")
    d.start()
    try:
        for k in range(3):
            d.offer(encode({"n": k}))
        assert _wait_for(lambda: d.stats()["delivered"] == 3)
        broker.stop()
        for k in range(3, 6):   # held in the queue while the broker is away
            d.offer(encode({"n": k}))
        time.sleep(0.3)
        assert d.stats()["delivered"] == 3
        broker.restart()        # paho reconnects (after 1 s, then 2 s, ...)
        assert _wait_for(lambda: d.stats()["delivered"] == 6, 15)
    finally:
        stats = d.close(time.monotonic() + 1)
    assert (stats["delivered"], stats["dropped"], stats["failed"]) == (6, 0, 0)
    assert stats["reconnects"] == 1


def test_mqtt_broker_that_is_down_does_not_stall_and_drops_are_counted(paho):
    d = MqttDelivery(MqttTarget("127.0.0.1", free_port()), "cam")
    d.start()
    t0 = time.monotonic()
    for k in range(5):
        d.offer(encode({"n": k}))
    stats = d.close(time.monotonic() + 0.5)
    assert time.monotonic() - t0 < 3.0
    assert (stats["events"], stats["delivered"], stats["dropped"]) == (5, 0, 5)


def test_second_interrupt_while_sinks_drain_stops_waiting_and_keeps_the_run(caplog):
    from motiontrack.run.event_sinks import EventSinksWriter

    class Draining:
        """A sink whose draining is interrupted by a second Ctrl-C."""

        def __init__(self):
            self.closes = []

        def start(self):
            pass

        def close(self, deadline):
            self.closes.append(deadline)
            if deadline is not None:
                raise KeyboardInterrupt
            return {"sink": "fake", "dropped": 1}

    a, b = Draining(), Draining()
    w = EventSinksWriter([a, b], "cam")
    w.start(None)
    w.close(keep=True)   # does not raise: the outputs of the run are kept
    # the first sink was waiting when interrupted, the second is not waited for at all
    assert a.closes[1:] == [None] and a.closes[0] is not None and b.closes == [None]
    assert w.stats() == [{"sink": "fake", "dropped": 1}] * 2
    assert "not waiting for the event sinks" in caplog.text


def test_sinks_receive_a_discontinuity_record_before_the_frames_events():
    """A receiver that keeps state per track (who is inside a zone) learns, in frame order, that
    the source jumped and that state was dropped, exactly as ``events.jsonl`` says it."""
    import numpy as np

    from motiontrack.run.event_sinks import EventSinksWriter
    from motiontrack.types import Discontinuity, Event, FrameResult, SceneFrame

    class Recording:
        def __init__(self):
            self.bodies = []

        def start(self):
            pass

        def offer(self, body):
            self.bodies.append(json.loads(body))

    sink = Recording()
    w = EventSinksWriter([sink], "door")
    w.start(None)
    event = Event("zone_exit", 121, 4.8, 7, 1.0, 2.0, zone="z", dwell_s=0.3)
    for scene in (SceneFrame(120), SceneFrame(121, (event,), discontinuity=Discontinuity("loop"))):
        w.write(FrameResult(index=scene.frame - 1, timestamp=0.0, frame=np.zeros((4, 4, 3), np.uint8),
                            mask=None, regions=(), tracks=(), scene=scene))
    assert sink.bodies == [{"type": "discontinuity", "reason": "loop", "frame": 121,
                            "camera": "door"}, {**event.to_json(), "camera": "door"}]
