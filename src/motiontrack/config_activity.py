"""Which config keys take effect: a key of a stage that does not run changes nothing.

Activity is read from the config's own structure, not from a list kept beside it:

* a per-method section takes effect only while its section's ``method`` names it
  (``motion.mog2.*`` while ``motion.method = mog2``);
* a field takes effect only while the switches its :func:`~motiontrack.config.param` names in
  ``when`` hold (``people.hog_every`` while ``people.hog`` is not ``off``), and those switches
  take effect themselves (``people.hog`` while ``people.enabled``).

:func:`activity` answers for one key of a resolved config, or for a study (a sweep's grid, a
tuning's search space, an ablation's rows): a key is active in a study when at least one of its
points activates it. Settings of the run that are not config keys (``--detections``,
``--save``, ``--show``, a live source) are outside this model: keys they switch on or off are
treated as active.
"""

from __future__ import annotations

import functools
import itertools
import logging
from dataclasses import dataclass
from typing import Any, Iterable, Mapping, Sequence

from .config_keys import config_fields, flatten
from .errors import ConfigError, printable
from .schema import Not

log = logging.getLogger(__name__)

__all__ = ["Activity", "activity", "inactive_in_study", "check_study_keys", "warn_inactive_overrides",
           "literal"]

#: most switch combinations :func:`activity` tries for a study (the switches of one key are few)
MAX_COMBINATIONS = 4096


@dataclass(frozen=True)
class Activity:
    """Whether ``key`` takes effect; when not, the switches that keep it off.

    ``needs`` holds ``(switch, its value now, a value that activates the key)``, each switch
    once, the fewest that do it (empty when the key is active).
    """

    key: str
    needs: tuple[tuple[str, Any, Any], ...] = ()

    @property
    def active(self) -> bool:
        return not self.needs

    @property
    def reason(self) -> str:
        """``"motion.method = knn"``: the settings that keep the key off."""
        return " and ".join(f"{k} = {literal(now, bare=True)}" for k, now, _ in self.needs)

    @property
    def settings(self) -> list[str]:
        """``["motion.method=mog2"]``: the ``--set`` values that activate the key."""
        return [f"{k}={literal(v, bare=True)}" for k, _, v in self.needs]

    def message(self, study: str = "") -> str:
        """One line for a user: the key, what keeps it off and how to switch it on; ``study``
        (``"sweep"``, ``"search"``) adds that varying the switch in the study works too."""
        sets = " ".join(f"--set {s}" for s in self.settings)
        alt = (f" (or {study} {' and '.join(k for k, _, _ in self.needs)})" if study else "")
        return f"{self.key} has no effect while {self.reason}; add {sets}{alt}"


def literal(value: Any, bare: bool = False) -> str:
    """A value as it is written in TOML (``true``, ``0.5``, ``"knn"``); with ``bare``, strings
    as ``--set`` takes them too (``knn``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return value if bare and value and value.isprintable() and " " not in value else \
            '"' + printable(value).replace('"', '\\"') + '"'
    return repr(value)


# ------------------------------------------------------------------------------- the schema
@functools.cache
def _schema() -> dict[str, Any]:
    """Every leaf key of :class:`PipelineConfig` → its dataclass field."""
    return {key: f for key, f, _ in config_fields()}


def _conditions(key: str) -> tuple[tuple[tuple[str, Any], ...], ...]:
    """The alternatives (any one must hold) of conditions (all must hold) under which ``key``
    takes effect, as ``(switch key, value or Not)``; one empty alternative when always."""
    parts = key.split(".")
    required: list[tuple[str, Any]] = []
    # a per-method section: ``a.b.<name>.x`` needs ``a.b.method = <name>``
    section_keys = _schema()
    for i in range(1, len(parts) - 1):
        parent = ".".join(parts[:i])
        method = f"{parent}.method" if parent else "method"
        if method in section_keys:
            required.append((method, parts[i]))
    f = section_keys[key]
    own = f.metadata.get("when") or ({},)
    section = ".".join(parts[:-1])
    return tuple(tuple(required) + tuple((f"{section}.{k}" if section else k, cond)
                                         for k, cond in alt.items()) for alt in own)


def _holds(cond: Any, value: Any) -> bool:
    if isinstance(cond, Not):
        return value != cond.value
    return value == cond


def _activating(cond: Any) -> Any:
    return cond.example if isinstance(cond, Not) else cond


def _needs(flat: Mapping[str, Any], key: str, seen: frozenset[str] = frozenset()
           ) -> list[tuple[str, Any, Any]] | None:
    """The switches to change so that ``key`` takes effect in the flat config, as
    ``(switch, value now, value needed)``: outer switches first, the fewest over the key's
    alternatives, never two that contradict each other; empty when it takes effect, None when
    no setting of the switches does."""
    best: list[tuple[str, Any, Any]] | None = None
    for alt in _conditions(key):
        state, fixes = dict(flat), {}
        for switch, cond in alt:
            if switch not in seen:  # the switch must take effect itself
                inner = _needs(state, switch, seen | {key})
                if inner is None:
                    break
                for k, _, v in inner:
                    state[k] = fixes[k] = v
            if not _holds(cond, state[switch]):
                state[switch] = fixes[switch] = _activating(cond)
        else:
            if fixes and _needs(state, key, seen) != []:
                continue  # one fix undid another: this alternative cannot be met
            unmet = [(k, flat[k], v) for k, v in fixes.items()]
            if best is None or len(unmet) < len(best):
                best = unmet
            if not unmet:
                break
    return best


def _switches(key: str, seen: frozenset[str] = frozenset()) -> set[str]:
    """Every key whose value can decide whether ``key`` takes effect."""
    out: set[str] = set()
    for alt in _conditions(key):
        for switch, _ in alt:
            if switch not in out and switch not in seen:
                out.add(switch)
                out |= _switches(switch, seen | {key})
    return out


def _check_key(key: str) -> None:
    if key not in _schema():
        raise ConfigError(f"unknown config key {key!r}")


# ------------------------------------------------------------------------------- the answers
def activity(cfg: Any, key: str, points: Iterable[Mapping[str, Any]] | None = None) -> Activity:
    """Whether ``key`` (dotted, as users write it) takes effect with the resolved config ``cfg``
    (a :class:`~motiontrack.config.PipelineConfig` or its nested dict).

    With ``points`` (overrides ``{key: value}`` applied to ``cfg`` one point at a time, e.g. the
    rows of an ablation) it is active when any point activates it; when none does, the answer
    says what keeps it off in ``cfg`` itself. An unknown key is a :class:`ConfigError`.
    """
    _check_key(key)
    flat = flatten(cfg)
    for point in points if points is not None else ({},):
        if _needs({**flat, **point}, key) == []:
            return Activity(key)
    return Activity(key, tuple(_needs(flat, key) or ()))


def inactive_in_study(cfg: Any, keys: Iterable[str], domains: Mapping[str, Sequence[Any]]
                      ) -> list[Activity]:
    """The ``keys`` that no point of a study activates, each with what keeps it off in ``cfg``.

    ``domains`` maps each varied key to values it takes (a sweep's values; a tuning range's two
    ends stand for it); the points are every combination of the varied keys that can switch a
    key on, so a sweep over ``motion.method`` activates the ``motion.mog2.*`` keys it varies
    together with it.
    """
    flat = flatten(cfg)
    out = []
    for key in keys:
        _check_key(key)
        varied = sorted(_switches(key) & set(domains))
        combos = itertools.islice(itertools.product(*(domains[k] for k in varied)),
                                  MAX_COMBINATIONS)
        act = activity(flat, key, (dict(zip(varied, c)) for c in combos))
        if not act.active:
            out.append(act)
    return out


def check_study_keys(cfg: Any, domains: Mapping[str, Sequence[Any]], what: str = "sweep") -> None:
    """Refuse a study that varies a key no point of it activates: every run would score the
    same and a "best" value would mean nothing. ``what`` is the verb of the hint (``sweep``,
    ``search``)."""
    dead = inactive_in_study(cfg, domains, domains)
    if dead:
        raise ConfigError(f"--param {dead[0].message(what)}"
                          + (f"; likewise {', '.join(a.key for a in dead[1:])}" if dead[1:] else ""))


def warn_inactive_overrides(cfg: Any, overrides: Iterable[str],
                            domains: Mapping[str, Sequence[Any]] | None = None,
                            points: Sequence[Mapping[str, Any]] | None = None,
                            reads: tuple[str, tuple[str, ...]] | None = None) -> list[str]:
    """Warn once for each ``--set key=value`` of ``overrides`` whose key does not take effect in
    ``cfg`` (nor at any point of a study's ``domains`` or ``points``); returns the keys warned
    about. Overrides are assumed valid (:func:`~motiontrack.config.apply_overrides` ran).

    ``reads`` is ``(what, sections)`` for a command that reads only some sections
    (``("dense flow", ("source", "motion.farneback", "output"))``): a key outside them is
    warned about as such.
    """
    warned = []
    for item in overrides:
        key = item.split("=", 1)[0].strip()
        if key not in _schema() or key in warned:
            continue
        if reads and not any(key == r or key.startswith(r + ".") for r in reads[1]):
            log.warning("--set %s has no effect on %s, which reads only %s", key, reads[0],
                        ", ".join(f"{r}.*" for r in reads[1]))
            warned.append(key)
            continue
        if domains:
            dead = inactive_in_study(cfg, [key], domains)
            act = dead[0] if dead else Activity(key)
        else:
            act = activity(cfg, key, points)
        if not act.active:
            log.warning("--set %s", act.message())
            warned.append(key)
    return warned
