"""``motiontrack serve CAMERAS.toml``: live cameras, their events and a scene editor in the
browser."""

from __future__ import annotations

import argparse
import logging
import os

log = logging.getLogger("motiontrack")

TOKEN_ENV = "MOTIONTRACK_TOKEN"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "serve", help="live cameras in the browser: pictures, events, counts, scene editor",
        description="Run every camera of CAMERAS.toml in a process of its own (tracks, events "
                    "and summary per camera under --out, in segments) and serve a web page and "
                    "a JSON API with their annotated pictures, events and counts, and an editor "
                    "of their scene files (docs/serve.md).")
    p.add_argument("cameras", nargs="?",
                   help="cameras file (TOML, [[camera]] tables: name, source, scene, "
                        "config, preset, camera, loop, fps)")
    p.add_argument("--review", metavar="DIR",
                   help="instead of cameras: the review page of a finished run's event store "
                        "(DIR/events.db of a track --scene, batch or serve output folder)")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1; any other needs a token)")
    p.add_argument("--port", type=int, default=8080, help="port (default 8080)")
    p.add_argument("--out", help="output folder, one subfolder per camera (default "
                                 "runs/serve/<cameras file name>)")
    p.add_argument("--allowed-host", action="append", default=[], metavar="NAME",
                   help="one more host name the server answers to (repeatable): the name of "
                        "this machine or of a reverse proxy in front of it; by default only "
                        "the --host address (and localhost for a loopback one) is answered, "
                        "which keeps other sites' pages out (docs/serve.md, Security model)")
    p.add_argument("--token", help=f"require this token on every request (Authorization: Bearer "
                                   f"or ?token=); default: the environment variable {TOKEN_ENV}")
    p.add_argument("--rotate-s", type=float, default=3600.0,
                   help="start a new output segment after this many seconds (default 3600)")
    p.add_argument("--rotate-mb", type=float, default=0.0,
                   help="start a new output segment when one reaches this many megabytes "
                        "(default 0: no size limit)")
    p.add_argument("--keep-days", type=float, default=None, metavar="D",
                   help="remove output segments (with their events, snapshots and clips) that "
                        "ended more than D days ago (default: keep all)")
    p.add_argument("--keep-gb", type=float, default=None, metavar="G",
                   help="remove the oldest output segments while all take more than G "
                        "gigabytes (default: no bound); never a segment being written")
    p.set_defaults(func=cmd_serve)


def cmd_serve(args) -> int:
    from ..errors import ConfigError
    from ..serve.hosts import is_loopback

    token = args.token or os.environ.get(TOKEN_ENV) or None
    if not is_loopback(args.host) and not token:
        raise ConfigError(f"--host {args.host} is reachable from other machines: give --token "
                          f"or set {TOKEN_ENV} (every request then needs it)")
    if not 0 < args.port < 65536:
        raise ConfigError(f"--port must be in 1..65535, got {args.port}")
    if (args.cameras is None) == (args.review is None):
        raise ConfigError("give a cameras file, or --review DIR, not both")
    try:
        from ..serve.retention import Retention
        from ..serve.review import review
        from ..serve.server import serve
    except ImportError as exc:
        raise ConfigError(f"serve needs the web extras ({exc.name} is missing): pip install "
                          "'motiontrack[serve]'") from None
    if args.review is not None:
        return review(args.review, args.host, args.port, token, allowed=args.allowed_host)
    return serve(args.cameras, args.host, args.port, args.out, token, rotate_s=args.rotate_s,
                 rotate_mb=args.rotate_mb, log_level=log.getEffectiveLevel(),
                 allowed=args.allowed_host,
                 retention=Retention(args.keep_days, args.keep_gb))
