"""Event delivery beyond the file: a webhook (one HTTP POST per event) and MQTT (one message per
event), each from a background thread fed through a bounded queue.

The pipeline hands a delivery encoded events with :meth:`Delivery.offer`, which never blocks: a
full queue drops the event and counts it. The thread sends the events in order; what it could
not send when the run ends is counted as dropped, so that for every sink

    events == delivered + failed + dropped

:meth:`Delivery.close` waits for the queue to drain at most until a deadline, so a receiver that
is down or never answers delays the end of a run by at most that long.

* :class:`WebhookDelivery` uses the standard library's ``urllib.request`` (no extra dependency;
  one small POST at a time needs nothing more). Connection errors, time-outs, ``408``, ``429``
  and ``5xx`` answers are retried with exponential back-off; other answers (``3xx``, ``4xx``)
  fail the event at once, since sending it again would not change them.
* :class:`MqttDelivery` uses ``paho-mqtt`` (the ``mqtt`` extra): QoS 1, paho's network loop
  reconnects with back-off and sends again the messages the broker had not acknowledged; an
  event is delivered when the broker acknowledges it (``PUBACK``).
"""

from __future__ import annotations

import base64
import http.client
import json
import logging
import math
import queue
import re
import threading
import time
import urllib.error
import urllib.request
import uuid
from dataclasses import dataclass
from typing import Any, Callable
from urllib.parse import unquote, urlsplit, urlunsplit

from ..errors import ConfigError, printable

log = logging.getLogger(__name__)

__all__ = ["WebhookTarget", "MqttTarget", "parse_webhook", "parse_mqtt", "check_camera_name",
           "Delivery", "WebhookDelivery", "MqttDelivery", "SinkSettings", "QUEUE_SIZE", "FLUSH_S"]

#: events a sink holds while its receiver is slow or away; more are dropped (and counted)
QUEUE_SIZE = 1000
#: seconds a run waits at its end for the sinks to send what they hold
FLUSH_S = 5.0
#: webhook: seconds one request may take, retries of one event, first back-off and its cap
TIMEOUT_S = 5.0
RETRIES = 5
BACKOFF_S = 0.5
BACKOFF_MAX_S = 30.0
#: MQTT: messages sent and not yet acknowledged at once; seconds a connection attempt may take
MQTT_WINDOW = 100
MQTT_CONNECT_TIMEOUT_S = 5.0

_CAMERA = re.compile(r"^[\w.-]{1,64}$")


@dataclass(frozen=True)
class SinkSettings:
    """How every sink of a run sends (``--sink-queue``, ``--sink-timeout``, ``--sink-retries``,
    ``--sink-wait``): the events it may hold while its receiver is slow or away, the seconds a
    webhook request (or an MQTT connection attempt) may take, a webhook's retries of one event,
    and the seconds the run waits at its end for what the sinks still hold."""

    queue_size: int = QUEUE_SIZE
    timeout_s: float = TIMEOUT_S
    retries: int = RETRIES
    flush_s: float = FLUSH_S

    def __post_init__(self) -> None:
        checks = (("--sink-queue", self.queue_size, self.queue_size >= 1, "at least 1"),
                  ("--sink-timeout", self.timeout_s,
                   math.isfinite(self.timeout_s) and self.timeout_s > 0, "seconds > 0"),
                  ("--sink-retries", self.retries, self.retries >= 0, "0 or more"),
                  ("--sink-wait", self.flush_s,
                   math.isfinite(self.flush_s) and self.flush_s >= 0, "seconds >= 0"))
        for option, value, ok, want in checks:
            if not ok:
                raise ConfigError(f"{option} must be {want}, got {value}")


# ----------------------------------------------------------------------------------- targets
@dataclass(frozen=True)
class WebhookTarget:
    """Where a webhook posts: ``url`` without credentials, ``authorization`` the HTTP Basic
    header built from the user and password the URL carried (or None)."""

    url: str
    authorization: str | None = None

    def describe(self) -> str:
        return self.url


@dataclass(frozen=True)
class MqttTarget:
    """An MQTT broker and the topic prefix: events go to ``<prefix>/<camera>/events``."""

    host: str
    port: int
    prefix: str = "motiontrack"
    tls: bool = False
    username: str | None = None
    password: str | None = None

    def topic(self, camera: str) -> str:
        return f"{self.prefix}/{camera}/events" if self.prefix else f"{camera}/events"

    def describe(self) -> str:
        scheme = "mqtts" if self.tls else "mqtt"
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{scheme}://{host}:{self.port}/{self.prefix}"


def _split(url: str, option: str, schemes: tuple[str, ...]):
    text = str(url)
    if not text.isprintable() or any(c.isspace() for c in text):
        raise ConfigError(f"{option} {printable(text)!r}: a URL has no spaces or control "
                          "characters")
    try:
        parts = urlsplit(text)
    except ValueError as exc:   # an unclosed [ of an IPv6 address
        raise ConfigError(f"{option} {_redacted(text)!r} is not a valid URL: {exc}") from None
    if parts.scheme.lower() not in schemes:
        raise ConfigError(f"{option} needs a {' or '.join(s + '://' for s in schemes)} URL, got "
                          f"{_redacted(text)!r}")
    try:
        port = parts.port
    except ValueError:
        raise ConfigError(f"{option} {_redacted(text)!r}: the port must be a number in "
                          "[1, 65535]") from None
    if not parts.hostname:
        raise ConfigError(f"{option} {_redacted(text)!r} names no host")
    if port == 0:
        raise ConfigError(f"{option} {_redacted(text)!r}: the port must be a number in "
                          "[1, 65535]")
    if parts.fragment:
        raise ConfigError(f"{option} {_redacted(text)!r}: a URL fragment (#...) is not sent; "
                          "leave it out")
    return parts, port


def _redacted(url: str) -> str:
    """``url`` without its user name and password (for messages and summaries)."""
    try:
        parts = urlsplit(url)
    except ValueError:   # not a URL: whatever stands between // and the last @ goes
        return re.sub(r"(//)[^/]*@", r"\1", url, count=1)
    if "@" not in parts.netloc:
        return url
    return urlunsplit(parts._replace(netloc=parts.netloc.rsplit("@", 1)[1]))


def parse_webhook(url: str) -> WebhookTarget:
    """An ``http://`` or ``https://`` URL (``--webhook``); ``user:password@`` in it becomes an
    HTTP Basic ``Authorization`` header. Raises :class:`ConfigError` naming the problem."""
    parts, _ = _split(url, "--webhook", ("http", "https"))
    auth = None
    if parts.username is not None:
        cred = f"{unquote(parts.username)}:{unquote(parts.password or '')}".encode()
        auth = "Basic " + base64.b64encode(cred).decode("ascii")
    return WebhookTarget(_redacted(urlunsplit(parts._replace(scheme=parts.scheme.lower()))),
                         auth)


def parse_mqtt(url: str) -> MqttTarget:
    """``mqtt://[user:password@]host[:port][/prefix]`` (``--mqtt``; ``mqtts://`` for TLS with
    the system's certificate authorities). Port 1883 (8883 with TLS) and prefix
    ``motiontrack`` by default. Raises :class:`ConfigError` naming the problem."""
    if "#" in str(url):   # a wildcard to MQTT, the start of a fragment to a URL parser
        raise ConfigError(f"--mqtt {_redacted(str(url))!r}: the topic prefix may not hold '+', "
                          "'#' or empty levels")
    parts, port = _split(url, "--mqtt", ("mqtt", "mqtts"))
    if parts.query:
        raise ConfigError(f"--mqtt {_redacted(url)!r}: a query (?...) means nothing to MQTT; "
                          "leave it out")
    prefix = parts.path.strip("/") if parts.path not in ("", "/") else "motiontrack"
    if any(c in prefix for c in "+#\0") or "//" in prefix:
        raise ConfigError(f"--mqtt {_redacted(url)!r}: the topic prefix {prefix!r} may not hold "
                          "'+', '#' or empty levels")
    tls = parts.scheme.lower() == "mqtts"
    return MqttTarget(parts.hostname, port or (8883 if tls else 1883), prefix, tls,
                      unquote(parts.username) if parts.username is not None else None,
                      unquote(parts.password) if parts.password is not None else None)


def check_camera_name(name: str) -> str:
    """``name`` when it can stand in payloads and as one MQTT topic level: 1 to 64 letters,
    digits, ``_``, ``.`` or ``-``."""
    if not _CAMERA.match(str(name)):
        raise ConfigError(f"--camera-name must be 1 to 64 letters, digits, '_', '.' or '-' (one "
                          f"MQTT topic level), got {printable(name)!r}")
    return str(name)


# -------------------------------------------------------------------------------- deliveries
class Delivery:
    """A background sender with a bounded queue (see the module docstring).

    Subclasses implement :meth:`_send` (deliver one encoded event: True when delivered, False
    when it failed for good, None when the delivery is counted elsewhere or was abandoned) and
    may extend :meth:`start` and :meth:`_shutdown`. ``sleep``, when given, is called with each
    back-off delay instead of waiting it (a test's clock); a deadline still ends the back-off.
    """

    kind = "sink"

    def __init__(self, queue_size: int = QUEUE_SIZE, *,
                 sleep: Callable[[float], None] | None = None) -> None:
        if queue_size < 1:
            raise ValueError(f"queue_size must be >= 1, got {queue_size}")
        # called with each back-off delay instead of waiting it out: tests drive the back-off
        # without spending its seconds
        self._sleep = sleep
        self._queue: queue.Queue[bytes] = queue.Queue(maxsize=queue_size)
        self._lock = threading.Lock()
        self._stop = threading.Event()    # no more events: send what is queued, then end
        self._abort = threading.Event()   # the deadline passed: end now
        self._thread: threading.Thread | None = None
        self._frozen: dict[str, Any] | None = None
        self.events = self.delivered = self.failed = self.full_drops = self.retries = 0

    # --- the pipeline's side
    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name=f"motiontrack-{self.kind}",
                                        daemon=True)
        self._thread.start()

    def offer(self, body: bytes) -> bool:
        """Queue one encoded event; never blocks. False (and counted) when the queue is full."""
        with self._lock:
            if self._frozen is not None:
                return False
            self.events += 1
        try:
            self._queue.put_nowait(body)
            return True
        except queue.Full:
            with self._lock:
                self.full_drops += 1
                first = self.full_drops == 1
            if first:
                log.warning("%s %s cannot keep up: its queue of %d events is full, events are "
                            "dropped (counted in summary.json)", self.kind, self.describe(),
                            self._queue.maxsize)
            return False

    def close(self, deadline: float | None) -> dict[str, Any]:
        """End the sender: with a ``deadline`` (``time.monotonic()``), send what is queued until
        then; without one, at once. What is left counts as dropped. Returns :meth:`stats`;
        never raises and never waits past the deadline."""
        self._stop.set()
        if self._thread is not None and deadline is not None:
            while not self._settled() and time.monotonic() < deadline:
                time.sleep(0.01)
        self._abort.set()
        with self._lock:
            if self._frozen is None:
                self._frozen = self._counts()
        try:
            self._shutdown()
        except Exception as exc:  # the counts are final; a failing shutdown changes nothing
            log.debug("closing %s %s: %s", self.kind, self.describe(), exc)
        stats = self.stats()
        lost = stats["dropped"] + stats["failed"]
        if lost:
            log.warning("%s %s: %d of %d events not delivered (%d dropped, %d failed)",
                        self.kind, self.describe(), lost, stats["events"], stats["dropped"],
                        stats["failed"])
        return stats

    def stats(self) -> dict[str, Any]:
        """``sink``, ``target``, ``events``, ``delivered``, ``failed``, ``dropped`` (queue full,
        or still unsent when the run ended), ``retries``."""
        with self._lock:
            counts = self._frozen if self._frozen is not None else self._counts()
        return {"sink": self.kind, "target": self.describe(), **counts}

    def describe(self) -> str:
        return self.kind

    # --- the thread's side
    def _counts(self) -> dict[str, Any]:
        dropped = self.events - self.delivered - self.failed
        return {"events": self.events, "delivered": self.delivered, "failed": self.failed,
                "dropped": dropped, "retries": self.retries}

    def _settled(self) -> bool:
        with self._lock:
            return self.delivered + self.failed + self.full_drops >= self.events

    def _count(self, name: str) -> None:
        with self._lock:
            if self._frozen is None:   # after close the counts are final
                setattr(self, name, getattr(self, name) + 1)

    def _run(self) -> None:
        while not self._abort.is_set():
            try:
                body = self._queue.get(timeout=0.05)
            except queue.Empty:
                if self._stop.is_set():
                    break
                continue
            try:
                ok = self._send(body)
            except Exception as exc:   # a sender bug must not end delivery silently
                log.warning("%s %s: %s", self.kind, self.describe(), exc)
                ok = False
            if ok is True:
                self._count("delivered")
            elif ok is False:
                self._count("failed")

    def _wait(self, seconds: float) -> bool:
        """Sleep up to ``seconds``; True when the deadline passed meanwhile."""
        if self._sleep is not None:
            self._sleep(seconds)
            return self._abort.is_set()
        return self._abort.wait(seconds)

    def _send(self, body: bytes) -> bool | None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _shutdown(self) -> None:
        """Release connections (after the counts are final)."""


class _NoRedirect(urllib.request.HTTPRedirectHandler):
    """A redirect is an answer, not a new address to post to: urllib would turn the POST into
    a GET without the event."""

    def redirect_request(self, req, fp, code, msg, headers, newurl):  # noqa: D102
        return None


class WebhookDelivery(Delivery):
    """POST each event as a JSON body to ``target`` (see the module docstring)."""

    kind = "webhook"

    def __init__(self, target: WebhookTarget, *, queue_size: int = QUEUE_SIZE,
                 timeout_s: float = TIMEOUT_S, retries: int = RETRIES,
                 backoff_s: float = BACKOFF_S, backoff_max_s: float = BACKOFF_MAX_S,
                 sleep: Callable[[float], None] | None = None) -> None:
        super().__init__(queue_size, sleep=sleep)
        self.target = target
        self.timeout_s, self.max_retries = float(timeout_s), int(retries)
        self.backoff_s, self.backoff_max_s = float(backoff_s), float(backoff_max_s)
        self._opener = urllib.request.build_opener(_NoRedirect)
        self._warned = False

    def describe(self) -> str:
        return self.target.describe()

    def _request(self, body: bytes) -> urllib.request.Request:
        headers = {"Content-Type": "application/json", "User-Agent": "motiontrack"}
        if self.target.authorization:
            headers["Authorization"] = self.target.authorization
        return urllib.request.Request(self.target.url, data=body, headers=headers, method="POST")

    def _send(self, body: bytes) -> bool | None:
        delay = self.backoff_s
        for attempt in range(self.max_retries + 1):
            if attempt:
                self._count("retries")
                if self._wait(delay):
                    return None
                delay = min(delay * 2, self.backoff_max_s)
            try:
                with self._opener.open(self._request(body), timeout=self.timeout_s) as resp:
                    resp.read()
                return True
            except urllib.error.HTTPError as exc:
                exc.close()
                if not (exc.code >= 500 or exc.code in (408, 429)):
                    self._warn(f"answered {exc.code} {exc.reason}; the event is not sent again")
                    return False
                self._warn(f"answered {exc.code} {exc.reason}; retrying")
            except (OSError, http.client.HTTPException) as exc:   # URLError, time-outs, resets
                reason = getattr(exc, "reason", None) or exc
                self._warn(f"{reason}; retrying")
            if self._abort.is_set():
                return None
        return False

    def _warn(self, what: str) -> None:
        if not self._warned:   # once: a receiver that is down would fill the log
            self._warned = True
            log.warning("webhook %s: %s", self.describe(), printable(what))


class MqttDelivery(Delivery):
    """Publish each event with QoS 1 to ``target.topic(camera)`` (see the module docstring)."""

    kind = "mqtt"

    def __init__(self, target: MqttTarget, camera: str, *, queue_size: int = QUEUE_SIZE,
                 window: int = MQTT_WINDOW,
                 connect_timeout_s: float = MQTT_CONNECT_TIMEOUT_S) -> None:
        super().__init__(queue_size)
        mqtt = _paho()
        self.target = target
        self.topic = target.topic(check_camera_name(camera))
        self._window = threading.BoundedSemaphore(window)
        self._connected = threading.Event()
        self._pending: set[int] = set()
        self._early: set[int] = set()   # acknowledged before publish() returned its id
        self._mqtt = mqtt
        client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2,
                             client_id=f"motiontrack-{camera}-{uuid.uuid4().hex[:8]}")
        client.connect_timeout = connect_timeout_s
        client.reconnect_delay_set(1, 30)
        if target.username is not None:
            client.username_pw_set(target.username, target.password)
        if target.tls:
            client.tls_set()
        client.on_connect = self._on_connect
        client.on_disconnect = self._on_disconnect
        client.on_publish = self._on_publish
        client.on_connect_fail = self._on_connect_fail
        self._client = client
        self._lost = False
        self.reconnects = 0
        self._connects = 0

    def describe(self) -> str:
        return self.target.describe()

    def stats(self) -> dict[str, Any]:
        return {**super().stats(), "topic": self.topic, "reconnects": self.reconnects}

    def start(self) -> None:
        self._client.connect_async(self.target.host, self.target.port, keepalive=30)
        self._client.loop_start()   # paho's thread: connects, reconnects, sends, acknowledges
        super().start()

    # paho's callbacks (its network thread)
    def _on_connect(self, client, userdata, flags, reason_code, properties) -> None:
        if reason_code.is_failure:
            self._warn_lost(f"refused the connection: {reason_code}")
            return
        self._connects += 1
        self.reconnects = self._connects - 1
        if self._lost:
            log.info("mqtt %s: connected again", self.describe())
        self._lost = False
        self._connected.set()

    def _on_disconnect(self, client, userdata, flags, reason_code, properties) -> None:
        self._connected.clear()
        self._warn_lost(f"connection lost ({reason_code}); reconnecting")

    def _on_connect_fail(self, client, userdata) -> None:
        self._warn_lost("cannot connect; retrying")

    def _warn_lost(self, what: str) -> None:
        if not self._lost and not self._abort.is_set():
            self._lost = True
            log.warning("mqtt %s: %s", self.describe(), what)

    def _on_publish(self, client, userdata, mid, reason_code, properties) -> None:
        with self._lock:
            if mid not in self._pending:
                self._early.add(mid)
                return
            self._pending.discard(mid)
        self._count("failed" if reason_code.is_failure else "delivered")
        self._window.release()

    # our sender thread
    def _send(self, body: bytes) -> bool | None:
        while not self._connected.wait(0.05):   # queue while the broker is away
            if self._abort.is_set():
                return None
        while not self._window.acquire(timeout=0.05):
            if self._abort.is_set():
                return None
        # not under self._lock: paho calls _on_publish holding its own lock, which publish()
        # takes too
        info = self._client.publish(self.topic, body, qos=1)
        failed = info.rc not in (self._mqtt.MQTT_ERR_SUCCESS, self._mqtt.MQTT_ERR_NO_CONN)
        acked = False
        if not failed:
            with self._lock:
                if info.mid in self._early:   # acknowledged before publish() returned
                    self._early.discard(info.mid)
                    acked = True
                else:
                    self._pending.add(info.mid)
        if failed:
            self._window.release()
            log.warning("mqtt %s: publishing failed (%s)", self.describe(),
                        self._mqtt.error_string(info.rc))
            return False
        if acked:
            self._window.release()
            return True
        return None   # delivered when the broker acknowledges it (_on_publish)

    def _shutdown(self) -> None:
        self._client.disconnect()
        # loop_stop joins paho's thread, which may be inside a connection attempt: wait a
        # moment for it, never longer (the thread is a daemon)
        stopper = threading.Thread(target=self._client.loop_stop, daemon=True)
        stopper.start()
        stopper.join(1.0)


def _paho():
    """The ``paho.mqtt.client`` module, or a :class:`ConfigError` telling how to install it."""
    try:
        import paho.mqtt.client as mqtt
    except ImportError:
        raise ConfigError("--mqtt needs paho-mqtt: pip install 'motiontrack[mqtt]'") from None
    if not hasattr(mqtt, "CallbackAPIVersion"):
        raise ConfigError("--mqtt needs paho-mqtt 2 or newer: pip install -U 'paho-mqtt>=2'")
    return mqtt


def require_mqtt() -> None:
    """Fail before a run when ``--mqtt`` is given and paho-mqtt is missing."""
    _paho()


def encode(payload: dict) -> bytes:
    """One event's body: its JSON object as events.jsonl writes it, UTF-8."""
    return json.dumps(payload).encode("utf-8")
