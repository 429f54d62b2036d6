"""The event-sink options that ``track`` and ``analyze`` share: ``--webhook``, ``--mqtt`` and
``--camera-name`` (docs/analytics.md, "Sinks")."""

from __future__ import annotations

import argparse


#: the --sink-* options: flag, type, default (those of motiontrack.io.sinks.SinkSettings, which
#: a plain run does not import), what it sets
_SETTINGS = (
    ("--sink-queue", int, 1000, "events each sink holds while its receiver is slow or away; "
                                "more are dropped and counted in summary.json"),
    ("--sink-timeout", float, 5.0, "seconds a webhook request or an MQTT connection attempt "
                                   "may take"),
    ("--sink-retries", int, 5, "times a webhook event is sent again after a failure, with "
                               "growing back-off"),
    ("--sink-wait", float, 5.0, "seconds the run waits at its end for the sinks to send what "
                                "they hold"),
)


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
    for flag, kind, default, what in _SETTINGS:
        g.add_argument(flag, type=kind, default=default, metavar="N" if kind is int else "S",
                       help=f"{what} (default {default:g})")


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


def sink_settings(args: argparse.Namespace):
    """The :class:`~motiontrack.io.sinks.SinkSettings` of the ``--sink-*`` options, checked
    (None without ``--webhook`` or ``--mqtt``: a run without sinks does not load them)."""
    if not (args.webhook or args.mqtt):
        return None
    from ..io.sinks import SinkSettings

    return SinkSettings(queue_size=args.sink_queue, timeout_s=args.sink_timeout,
                        retries=args.sink_retries, flush_s=args.sink_wait)


def sinks_writer(targets: list, camera_name: str | None, default_name: str, settings=None):
    """The writer sending events to ``targets`` as ``settings`` say (None without targets)."""
    if not targets:
        return None
    from ..run.event_sinks import sinks_writer as writer

    return writer(targets, camera_name or default_name, settings)
