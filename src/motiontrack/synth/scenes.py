"""Synthetic surveillance scenes with exact ground truth.

The registry of the built-in scenes (:data:`SCENES`), their overrides, and the two ways to make
one: :func:`make_scene` and the ``synth:NAME?key=value`` spec (:func:`parse_synth_spec`). Each
scene is built by a function of its family (:mod:`~motiontrack.synth.walkway`,
:mod:`~motiontrack.synth.analytics_scenes`) from the shared blocks of
:mod:`~motiontrack.synth.building` into a :class:`~motiontrack.synth.sequence.SyntheticScene`.

See ``docs/synthetic.md``.
"""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from ..errors import ConfigError
from .building import Ctx, street_layout
from .catalogue import SCENE_TYPES, SCENES
from .sequence import Lighting, SyntheticScene, stable_hash

__all__ = ["make_scene", "parse_synth_spec"]

# Override name -> (kind, check, description)
_OVERRIDES: dict[str, tuple[str, Callable[[Any], bool], str]] = {
    "n_frames": ("int", lambda v: 1 <= v <= 100_000, "an integer in [1, 100000]"),
    "width": ("int", lambda v: 64 <= v <= 4096, "an integer in [64, 4096]"),
    "height": ("int", lambda v: 64 <= v <= 4096, "an integer in [64, 4096]"),
    "fps": ("float", lambda v: 0 < v <= 1000, "a number in (0, 1000]"),
    "noise": ("float", lambda v: 0 <= v <= 64, "a number of grey levels in [0, 64]"),
    "shadows": ("bool", lambda v: True, "true or false"),
    "illumination": ("bool", lambda v: True, "true or false"),
}


def _coerce(key: str, value: Any) -> Any:
    kind, ok, what = _OVERRIDES[key]
    bad = ConfigError(f"synthetic scene parameter {key} must be {what}, got {value!r}")
    if kind == "bool":
        if isinstance(value, (bool, np.bool_)):
            return bool(value)
        if isinstance(value, (int, np.integer)) and value in (0, 1):
            return bool(value)
        raise bad
    if isinstance(value, (bool, np.bool_)):
        raise bad
    if kind == "int":
        if isinstance(value, (int, np.integer)):
            v = int(value)
        elif isinstance(value, (float, np.floating)) and float(value).is_integer():
            v = int(value)
        else:
            raise bad
    else:
        if not isinstance(value, (int, float, np.integer, np.floating)):
            raise bad
        v = float(value)
        if not math.isfinite(v):
            raise bad
    if not ok(v):
        raise bad
    return v


def make_scene(name: str, seed: int = 0, **overrides: Any) -> SyntheticScene:
    """Build a built-in synthetic scene.

    Parameters
    ----------
    name : str
        One of :data:`SCENES`.
    seed : int
        Non-negative seed; the same ``(name, seed, overrides)`` always gives the same scene.
    **overrides
        ``n_frames`` (int), ``width``/``height`` (int px; the layout, people's sizes and speeds
        scale with the frame), ``fps`` (float, metadata only), ``noise`` (sensor noise sigma in grey
        levels, default 3.5; 0 = none), ``shadows`` (bool, default False), ``illumination`` (bool,
        default True only in "lighting").

    Raises
    ------
    ConfigError
        Unknown scene name, unknown override or invalid value.
    """
    if name not in SCENE_TYPES:
        raise ConfigError(f"unknown synthetic scene {name!r}; valid names: {', '.join(SCENES)}")
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ConfigError(f"synthetic scene seed must be a non-negative integer, got {seed!r}")
    unknown = sorted(set(overrides) - set(_OVERRIDES))
    if unknown:
        raise ConfigError(
            f"unknown synthetic scene parameter(s) {', '.join(unknown)}; valid: seed, "
            + ", ".join(_OVERRIDES)
        )
    ov = {k: _coerce(k, v) for k, v in overrides.items()}
    st = SCENE_TYPES[name]
    width = ov.get("width", 640)
    height = ov.get("height", 480)
    n_frames = ov.get("n_frames", st.n_frames)
    rng = np.random.default_rng([int(seed), 3, stable_hash(name)])
    ctx = Ctx(rng=rng, width=width, height=height, n_frames=n_frames, horizon=0.15 * height)
    built = st.build(ctx)
    illumination = ov.get("illumination", built.get("illumination", False))
    return SyntheticScene(
        name=name,
        seed=int(seed),
        width=width,
        height=height,
        fps=ov.get("fps", 25.0),
        n_frames=n_frames,
        people=built["people"],
        bags=built.get("bags", ()),
        vehicles=built.get("vehicles", ()),
        scene_file=built.get("scene_file") or street_layout(ctx),
        column=built.get("column"),
        noise=ov.get("noise", 3.5),
        shadows=ov.get("shadows", False),
        lighting=Lighting.default(n_frames) if illumination else None,
        shadow_side=1.0 if rng.random() < 0.5 else -1.0,
        overrides=ov,
    )


_TRUE = {"true", "1", "yes", "on"}
_FALSE = {"false", "0", "no", "off"}


def parse_synth_spec(spec: str) -> SyntheticScene:
    """Build a scene from a spec string: ``"synth:NAME"`` or ``"synth:NAME?key=value&..."``.

    Keys: ``seed`` and the overrides of :func:`make_scene`. Booleans accept
    ``true/false/1/0/yes/no/on/off``.

    Raises
    ------
    ConfigError
        Missing ``synth:`` prefix, unknown scene or key, repeated key, or a bad value.
    """
    if not isinstance(spec, str) or not spec.startswith("synth:"):
        raise ConfigError(f"a synthetic scene spec must look like 'synth:NAME[?key=value&...]', "
                          f"got {spec!r}")
    body = spec[len("synth:"):]
    name, _, query = body.partition("?")
    name = name.strip()
    if not name:
        raise ConfigError(f"synthetic scene spec {spec!r} has no scene name; valid names: "
                          + ", ".join(SCENES))
    if name not in SCENE_TYPES:
        raise ConfigError(f"unknown synthetic scene {name!r}; valid names: {', '.join(SCENES)}")
    params = _spec_params(spec, query)
    seed = params.pop("seed", 0)
    return make_scene(name, seed, **params)


def _spec_params(spec: str, query: str) -> dict[str, Any]:
    """``{key: value}`` from the ``key=value&...`` part of ``spec``."""
    params: dict[str, Any] = {}
    for item in query.split("&") if query else []:
        if not item:
            continue
        key, eq, raw = item.partition("=")
        key, raw = key.strip(), raw.strip()
        if not eq or not key or not raw:
            raise ConfigError(f"synthetic scene spec {spec!r}: expected key=value, got {item!r}")
        if key in params:
            raise ConfigError(f"synthetic scene spec {spec!r}: parameter {key} given twice")
        params[key] = _spec_value(key, raw)
    return params


def _spec_value(key: str, raw: str) -> Any:
    """A spec value: ``seed`` an int, booleans from words, other overrides numbers (their
    ranges are checked by :func:`make_scene`)."""
    if key == "seed":
        try:
            return int(raw)
        except ValueError:
            raise ConfigError(f"synthetic scene seed must be a non-negative integer, "
                              f"got {raw!r}") from None
    if key not in _OVERRIDES:
        raise ConfigError(f"unknown synthetic scene parameter {key!r}; valid: seed, "
                          + ", ".join(_OVERRIDES))
    kind, _, what = _OVERRIDES[key]
    if kind == "bool":
        low = raw.lower()
        if low in _TRUE:
            return True
        if low in _FALSE:
            return False
        raise ConfigError(f"synthetic scene parameter {key} must be {what}, got {raw!r}")
    try:
        return float(raw)
    except ValueError:
        raise ConfigError(f"synthetic scene parameter {key} must be {what}, "
                          f"got {raw!r}") from None
