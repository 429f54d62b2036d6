"""``motiontrack config``: every config key with its type, range, default, meaning and value;
with ``--json-schema``, the JSON Schema of a file users write (the schemas load only then)."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "config", help="show every config key: type, range, default, meaning and resolved value",
        description="Print every config key (or those under KEY) with its value after --preset, "
                    "--config and --set, its type, allowed range, default and meaning. A '*' "
                    "marks a value that differs from the default, a '-' a key that has no effect "
                    "with these settings (the meaning then names the switch that turns it on). "
                    "--toml prints the resolved config as a config file instead; --json-schema "
                    "prints the JSON Schema (draft 2020-12) of the config, the scene file, "
                    "serve's cameras file or a sequences manifest, for editors.")
    p.add_argument("keys", nargs="*", metavar="KEY",
                   help="only these keys or sections, e.g. motion.knn or tracker.max_lost_s")
    p.add_argument("--preset", help="shipped settings to start from: people, fast, detections "
                                    "(see `motiontrack list`)")
    p.add_argument("--config", help="TOML config file (applied after --preset)")
    p.add_argument("--set", dest="overrides", action="append", default=[],
                   metavar="STAGE.PARAM=VALUE", help="override one config field (repeatable)")
    p.add_argument("--toml", action="store_true",
                   help="print the resolved config as TOML (a file for --config)")
    p.add_argument("--json-schema", nargs="?", const="config", choices=JSON_SCHEMA_FILES,
                   metavar="FILE", help="print the JSON Schema of a file: "
                                        f"{', '.join(JSON_SCHEMA_FILES)} (default config)")
    p.set_defaults(func=cmd_config)


#: the files ``--json-schema`` exports
JSON_SCHEMA_FILES = ("config", "scene", "cameras", "manifest")


def json_schema_of(file: str) -> dict:
    """The JSON Schema of one of :data:`JSON_SCHEMA_FILES` (the scene file with the tables of
    every registered rule)."""
    if file == "config":
        from ..config import PipelineConfig
        from ..schema import json_schema

        return json_schema(PipelineConfig, title="motiontrack pipeline config")
    if file == "scene":
        from ..analytics.scene import scene_json_schema

        return scene_json_schema()
    if file == "cameras":
        from ..serve.cameras import cameras_json_schema

        return cameras_json_schema()
    if file == "manifest":
        from ..io.manifest import manifest_json_schema

        return manifest_json_schema()
    raise ValueError(f"no JSON Schema of {file!r}; files: {', '.join(JSON_SCHEMA_FILES)}")


def cmd_config(args) -> int:
    from ..config import load_config, to_dict
    from ..config_activity import activity, literal, warn_inactive_overrides
    from ..config_keys import flatten, key_docs
    from ..errors import ConfigError

    if args.json_schema:
        if args.keys or args.toml or args.config or args.preset or args.overrides:
            raise ConfigError("--json-schema prints a file's schema; give it alone")
        import json

        print(json.dumps(json_schema_of(args.json_schema), indent=2, ensure_ascii=False))
        return 0
    cfg = load_config(args.config, args.overrides, preset=args.preset)
    warn_inactive_overrides(cfg, args.overrides)
    if args.toml:
        if args.keys:
            raise ConfigError("--toml prints the whole config; give no KEY with it")
        import tomli_w

        print(tomli_w.dumps(to_dict(cfg)), end="")
        return 0
    docs = [d for d in key_docs() if _selected(d.key, args.keys)]
    unknown = [k for k in args.keys if not any(_selected(d.key, [k]) for d in key_docs())]
    if unknown:
        sections = sorted({d.key.split(".")[0] for d in key_docs()})
        raise ConfigError(f"no config key or section {unknown[0]!r}; sections: "
                          f"{', '.join(sections)}")
    flat = flatten(cfg)
    rows = []
    for d in docs:
        value = flat[d.key]
        act = activity(flat, d.key)
        mark = ("*" if value != d.default else " ") + (" " if act.active else "-")
        meaning = d.meaning if act.active else f"[needs {' '.join(act.settings)}] {d.meaning}"
        rows.append((mark, d.key, literal(value), literal(d.default), d.type, d.allowed, meaning))
    head = ("", "key", "value", "default", "type", "allowed", "meaning")
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head) - 1)]
    for r in [head, *rows]:
        print("  ".join(c.ljust(w) for c, w in zip(r, widths)) + "  " + r[-1])
    print("* differs from the default   - has no effect with these settings")
    return 0


def _selected(key: str, wanted: list[str]) -> bool:
    return not wanted or any(key == w or key.startswith(w.rstrip(".") + ".") for w in wanted)

