"""The options that stand for config keys: one table, flag → key, type and meaning.

``--fps 10`` is ``--set source.fps=10.0``, ``--no-video`` is ``--set output.video=false``: every
command that has such an option (``track``, ``flow``, ``follow``) and ``serve``, whose cameras
file has keys of the same names, declare it with :func:`add_flag` and turn the values given into
``--set`` overrides with :func:`flag_overrides`, so a flag means the same key, with the same type,
everywhere. A flag's type is its key's type in :class:`~motiontrack.config.PipelineConfig`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

__all__ = ["Flag", "FLAGS", "flag", "add_flag", "flag_overrides", "key_literal"]


@dataclass(frozen=True)
class Flag:
    """One option that sets a config key.

    ``option`` as written on the command line (``--max-frames``); ``dest`` its name in parsed
    arguments and in the cameras file (``max_frames``); ``key`` the config key it sets and
    ``type`` that key's type (``int``, ``float``, ``bool``, ``str``: the same as in
    :class:`~motiontrack.config.PipelineConfig`, written here so that building the command line
    does not load the config); ``switch`` for an option without a value, the key's value when it
    is given (``--no-video`` sets ``output.video`` to ``False``), else ``None``; ``meaning`` the
    option's help.
    """

    option: str
    dest: str
    key: str
    type: type
    meaning: str
    switch: bool | None = None


#: every option that stands for a config key, in the order their overrides are applied
FLAGS: tuple[Flag, ...] = (
    Flag("--start", "start", "source.start", int, "first frame index (0-based)"),
    Flag("--max-frames", "max_frames", "source.max_frames", int,
         "process at most this many frames"),
    Flag("--fps", "fps", "source.fps", float,
         "frame rate to use instead of the source's own (source.fps), for footage stored at "
         "another rate than it was recorded at: durations in seconds, speeds and the output "
         "video follow it"),
    Flag("--codec", "codec", "output.codec", str, "video codec"),
    Flag("--no-video", "no_video", "output.video", bool, "analysis only: no annotated video",
         switch=False),
    Flag("--mask-video", "mask_video", "output.mask_video", bool,
         "also write the motion mask video",
         switch=True),
    Flag("--camera", "camera", "measure.camera", str,
         "calibrated camera (PETS/Tsai XML, OpenCV YAML, TOML): world positions in tracks.txt "
         "columns 8-9 (metres), per-track speed and height in summary.json"),
    Flag("--detector", "detector", "detector.model", str,
         "your own detector, onnx:MODEL.onnx: a YOLO-family ONNX model (YOLOv5, YOLOv8, YOLO11) "
         "whose boxes are fused with the motion regions (detector.mode) and give tracks their "
         "class"),
    Flag("--detector-names", "detector_names", "detector.names", str,
         "the detector's class names, one a line (default: the model's metadata)"),
)

_BY_DEST = {f.dest: f for f in FLAGS}
_BY_OPTION = {f.option: f for f in FLAGS}


def flag(name: str) -> Flag:
    """The :class:`Flag` of an option (``"--fps"``) or of its ``dest`` (``"fps"``)."""
    return _BY_OPTION.get(name) or _BY_DEST[name]


def add_flag(parser: Any, option: str, **kwargs: Any) -> Any:
    """Add ``option`` (one of :data:`FLAGS`) to an argparse ``parser``: a switch as
    ``store_true``, else with the type of its key; ``kwargs`` (a command's own ``help``,
    ``default``, ``action``) take precedence."""
    f = flag(option)
    opts: dict[str, Any] = {"help": f.meaning}
    if f.switch is not None:
        opts["action"] = "store_true"
    elif "action" not in kwargs and f.type is not str:
        opts["type"] = f.type
    opts.update(kwargs)
    return parser.add_argument(f.option, **opts)


def key_literal(value: Any, typ: type) -> str:
    """``value`` as a ``--set`` literal of a key of type ``typ`` (``10.0``, ``true``, ``"a b"``)."""
    if typ is bool:
        return "true" if value else "false"
    if typ is int:
        return str(int(value))
    if typ is float:
        return repr(float(value))
    return json.dumps(str(value))


def flag_overrides(values: Mapping[str, Any] | Any, dests: Iterable[str] | None = None
                   ) -> list[str]:
    """The ``--set`` overrides of the flags given, in :data:`FLAGS` order: ``values`` is parsed
    arguments (``argparse.Namespace``) or a mapping by ``dest``; a value that is ``None`` or
    empty (not given) or a switch left off adds nothing. ``dests`` limits the flags considered."""
    get = values.get if isinstance(values, Mapping) else (lambda d: getattr(values, d, None))
    wanted = None if dests is None else set(dests)
    out = []
    for f in FLAGS:
        if wanted is not None and f.dest not in wanted:
            continue
        v = get(f.dest)
        if v is None or v == "" or (f.switch is not None and not v):
            continue   # not given (an empty path or codec is "not given" too)
        out.append(f"{f.key}={key_literal(f.switch if f.switch is not None else v, f.type)}")
    return out
