"""Learner settings by key: text read once (``parse_settings``), typed changes applied (``apply_settings``).

A setting key is a field of a learner config (``gamma``, ``input_shape``, ``neighbourhood_q``), a
schedule or one of its parts (``alpha`` or ``alpha.scale``, ``alpha.floor``, ``alpha.decay``), or
``decay`` (every schedule's decay at once). The command line's ``--set KEY=VALUE``, a sweep's axes
and the ``overrides`` of a ``config.json`` are text: ``parse_settings`` turns them into typed values
once, at the front end, and nothing below sees the text. ``apply_settings`` makes typed changes to
a config, ``format_settings`` writes them as text again (``config.json``, a rerun's command line).

The kind of each field comes from its annotation in the config dataclass, so a new field of a
config is settable by key with no change here.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from somarm.learners.schedules import (
    Constant,
    ExponentialDecay,
    InverseDecay,
    parse_bool,
    parse_decay,
    parse_shape,
)
from somarm.validation import check_number, parse_float, parse_int

__all__ = ["allowed_keys", "parse_settings", "apply_settings", "format_settings", "format_setting"]

_DECAYS = (Constant, InverseDecay, ExponentialDecay)
#: What a typed value of each kind must be, for the one-line error of a wrong type.
_WANTED = {
    "number": "a number", "floor": "a number", "decay": "a Decay (InverseDecay, ExponentialDecay or Constant; "
    "schedules.parse_decay reads 'inv:TAU', 'exp:C', 'const')", "shape": "a tuple of 1 or 2 whole numbers",
    "bool": "True or False", "int": "a whole number", "float": "a number", "optional_float": "a number or None",
    "range": "a (low, high) pair of numbers or None", "text": "a str",
}


def _field_kinds(cls: type) -> dict[str, str]:
    """Each field's kind, read from its annotation: schedule, shape, bool, int, float, ..., text."""
    kinds = {}
    for field in dataclasses.fields(cls):
        annotation = field.type if isinstance(field.type, str) else getattr(field.type, "__name__", str(field.type))
        annotation = annotation.replace(" ", "")
        if field.name in cls.SCHEDULES:
            kinds[field.name] = "schedule"
        elif annotation.startswith("tuple[int"):
            kinds[field.name] = "shape"
        elif annotation.startswith("tuple[float"):
            kinds[field.name] = "range"
        elif annotation in ("bool", "int", "float"):
            kinds[field.name] = annotation
        elif annotation in ("float|None", "None|float"):
            kinds[field.name] = "optional_float"
        else:
            kinds[field.name] = "text"
    return kinds


def allowed_keys(cls: type) -> str:
    """The keys a config class takes, as the error of an unknown key lists them."""
    kinds = _field_kinds(cls)
    schedules = [f"{name}[.scale|.floor|.decay]" for name in cls.SCHEDULES]
    others = [name for name, kind in kinds.items() if kind != "schedule"]
    return ", ".join((["decay"] if cls.SCHEDULES else []) + schedules + others)


def _key_kind(cls: type, key: str) -> str:
    """The kind of a setting key: ``decay``, ``number`` (a schedule's scale), ``floor``, or a field's kind.

    Raises:
      ValueError: an unknown key (the allowed keys are listed).
    """
    kinds = _field_kinds(cls)
    name, dot, part = str(key).partition(".")
    if key == "decay" and cls.SCHEDULES:
        return "decay"
    if kinds.get(name) == "schedule" and part in ("", "scale") and not (dot and not part):
        return "number"
    if kinds.get(name) == "schedule" and part in ("floor", "decay"):
        return part
    if not dot and name in kinds and kinds[name] != "schedule":
        return kinds[name]
    raise ValueError(f"unknown key {key!r}; allowed keys: {allowed_keys(cls)}")


def _parse(kind: str, key: str, text: str) -> Any:
    name = key.partition(".")[0]
    if kind == "decay":
        return parse_decay(text)
    if kind in ("number", "floor"):
        return check_number(name if kind == "number" else key, parse_float(key, text), minimum=0.0)
    if kind == "shape":
        return parse_shape(name, text)
    if kind == "bool":
        return parse_bool(name, text)
    if kind == "range":
        return None if text.lower() == "none" else tuple(parse_float(key, v) for v in text.replace(",", ":").split(":"))
    if kind == "float":
        return parse_float(key, text)
    try:
        if kind == "optional_float":
            return None if text.lower() == "none" else parse_float(key, text)
        if kind == "int":
            return parse_int(key, text)
    except ValueError:
        raise ValueError(f"{key} must be {'a number or none' if kind == 'optional_float' else 'a whole number'}") \
            from None
    return text


def parse_settings(cls: type, texts: dict[str, str]) -> dict[str, Any]:
    """Text settings (``{"alpha": "0.5", "decay": "inv:250"}``) as the typed values ``apply_settings`` takes.

    Args:
      cls: the learner config class (``learners.config_class(kind)``).
      texts: ``--set`` values by key.

    Returns:
      The same keys with typed values (numbers, ``Decay`` objects, shape tuples, bools, ...).

    Raises:
      ValueError: an unknown key (the allowed keys are listed) or a value of the wrong form, in one
        line starting with ``KEY=VALUE``.
    """
    out = {}
    for key, text in texts.items():
        kind = _key_kind(cls, key)
        try:
            out[key] = _parse(kind, key, str(text).strip())
        except ValueError as exc:
            raise ValueError(f"{key}={text}: {exc}") from None
    return out


def _typed(kind: str, key: str, value: Any) -> Any:
    """A typed value checked for its kind (numbers as floats); ValueError naming what was wanted."""
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if kind in ("number", "floor", "float") and number:
        if kind == "float":
            return float(value)
        return check_number(key.partition(".")[0] if kind == "number" else key, float(value), minimum=0.0)
    if kind == "optional_float" and (value is None or number):
        return None if value is None else float(value)
    if kind == "decay" and isinstance(value, _DECAYS):
        return value
    if kind == "shape" and isinstance(value, (tuple, list)) and all(
            isinstance(v, int) and not isinstance(v, bool) for v in value):
        return tuple(value)
    if kind == "range" and (value is None or (isinstance(value, (tuple, list)) and len(value) == 2 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value))):
        return None if value is None else tuple(float(v) for v in value)
    if (kind == "bool" and isinstance(value, bool)) or (kind == "int" and isinstance(value, int)
                                                         and not isinstance(value, bool)):
        return value
    if kind == "text" and isinstance(value, str):
        return value
    given = f"the text {value!r} (parse text with parse_settings)" if isinstance(value, str) else repr(value)
    raise ValueError(f"{key} must be {_WANTED[kind]}, got {given}")


def apply_settings(config: Any, changes: dict[str, Any]) -> Any:
    """A copy of a learner config with typed changes made in order, each checked as it is made.

    A change that leaves the config inconsistent with another setting may be made good by a later change
    (``local_linear=False`` then ``shared_slopes=False``, in either order); the error, when none does,
    names the change after which the config never was consistent again.

    Args:
      config: a learner config (``SOMQConfig``, ``MotoricConfig``, ``TabularConfig``).
      changes: typed values by setting key, e.g. ``{"epsilon": 0.2, "decay": InverseDecay(1000.0),
        "input_shape": (10, 10), "neighbourhood_q": False}``.

    Returns:
      The changed config (the same class).

    Raises:
      ValueError: an unknown key, a value of the wrong type or out of range (one line naming the key).
    """
    cls = type(config)
    fields = {field.name: getattr(config, field.name) for field in dataclasses.fields(config)}
    unmended = None  # the error of the change after which the config has not been consistent
    for key, value in changes.items():
        kind = _key_kind(cls, key)
        name, _, part = str(key).partition(".")
        value = _typed(kind, key, value)
        try:
            if kind == "decay" and key == "decay":
                for schedule in cls.SCHEDULES:
                    fields[schedule] = fields[schedule].with_changes(decay=value)
            elif kind == "number":
                fields[name] = fields[name].with_changes(scale=value)
            elif kind in ("floor", "decay"):
                fields[name] = fields[name].with_changes(**{part: value})
            else:
                fields[name] = value
        except ValueError as exc:
            raise ValueError(f"{key}={format_setting(value)}: {exc}") from None
        try:
            cls(**fields)  # checked now, so the error names this key
            unmended = None
        except ValueError as exc:
            unmended = unmended or ValueError(f"{key}={format_setting(value)}: {exc}")
    if unmended is not None:
        raise unmended
    return cls(**fields)


def format_setting(value: Any) -> str:
    """A typed setting as the text ``parse_settings`` reads back to an equal value (``2.0`` as ``2``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        text = repr(value)
        return text[:-2] if text.endswith(".0") else text
    if isinstance(value, _DECAYS):
        kind, _, number = value.to_text().partition(":")
        return f"{kind}:{format_setting(float(number))}" if number else kind
    if value is None:
        return "none"
    if isinstance(value, tuple) and value and all(isinstance(v, float) for v in value):
        return ":".join(format_setting(v) for v in value)
    if isinstance(value, tuple):
        return "x".join(str(v) for v in value)
    return str(value)


def settings_of(config: Any) -> dict[str, Any]:
    """Every setting of ``config`` by key, typed: each schedule as ``NAME``, ``NAME.decay`` and
    ``NAME.floor``, each other field by name. ``with_changes`` of them on any config gives ``config``."""
    out: dict[str, Any] = {}
    for f in dataclasses.fields(config):
        value = getattr(config, f.name)
        if f.name in type(config).SCHEDULES:
            out.update({f.name: value.scale, f"{f.name}.decay": value.decay, f"{f.name}.floor": value.floor})
        else:
            out[f.name] = value
    return out


def format_settings(changes: dict[str, Any]) -> dict[str, str]:
    """Typed settings as text by key (the inverse of ``parse_settings``)."""
    return {key: format_setting(value) for key, value in changes.items()}
