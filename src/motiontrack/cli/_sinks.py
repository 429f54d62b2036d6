"""The event-sink options that ``track`` and ``analyze`` share: ``--webhook``, ``--mqtt`` and
``--camera-name`` (docs/analytics.md, "Sinks")."""

from __future__ import annotations

import argparse


def add_sink_options(p: argparse.ArgumentParser, default_name: str) -> None:
    g = p.add_argument_group("event sinks (with --scene; docs/analytics.md)")
    g.add_argument("--webhook", action="append", default=[], metavar="URL",
                   help="POST every event as JSON to this http(s) URL (repeatable); "
                        "user:password@ in the URL is sent as HTTP Basic authorization")
    g.add_argument("--mqtt", action="append", default=[], metavar="URL",
                   help="publish every event (QoS 1) to mqtt://[user:password@]host[:port]"
                        "[/prefix] (mqtts:// for TLS; repeatable) on the topic "
                        "PREFIX/CAMERA/events (prefix default motiontrack); needs the mqtt "
                        "extra: pip install 'motiontrack[mqtt]'")
    g.add_argument("--camera-name", metavar="NAME",
                   help="the camera's name in every sent event (\"camera\") and in the MQTT "
                        f"topic (default: {default_name})")


def sink_targets(args: argparse.Namespace) -> list:
    """The targets of ``--webhook`` and ``--mqtt``, checked (a bad URL, a bad camera name or a
    missing paho-mqtt is a :class:`~motiontrack.errors.ConfigError` before the run starts)."""
    if not (args.webhook or args.mqtt or args.camera_name is not None):
        return []   # nothing to check: a run without sinks does not load them
    from ..io.sinks import check_camera_name, parse_mqtt, parse_webhook, require_mqtt

    targets = [parse_webhook(u) for u in args.webhook] + [parse_mqtt(u) for u in args.mqtt]
    if args.mqtt:
        require_mqtt()
    if args.camera_name is not None:
        check_camera_name(args.camera_name)
    return targets


def sinks_writer(targets: list, camera_name: str | None, default_name: str):
    """The writer sending events to ``targets`` (None without targets)."""
    if not targets:
        return None
    from ..run.event_sinks import EventSinksWriter, deliveries

    name = camera_name or default_name
    return EventSinksWriter(deliveries(targets, name), name)
