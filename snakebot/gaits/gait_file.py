"""Gait files: TOML naming a gait, its [params] and a free-form [meta] table kept as is."""

from __future__ import annotations

import datetime as dt
import math
import re
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from snakebot.config.fields import read_toml, shown_key
from snakebot.errors import ConfigError, GaitError
from snakebot.gaits.registry import gait_names, get_spec
from snakebot.gaits.spec import coerce_value

_TOP_KEYS = ("gait", "params", "meta")
MAX_GAIT_VALUE = 1e6
"""Largest magnitude of a number in a gait file's [params]: 1e308 there is a typo."""
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_ESCAPES = {
    '"': '\\"',
    "\\": "\\\\",
    "\b": "\\b",
    "\t": "\\t",
    "\n": "\\n",
    "\f": "\\f",
    "\r": "\\r",
}


def load_gait_file(path: str | Path) -> tuple[str, dict[str, object], dict[str, object]]:
    """Read (gait name, typed params, meta) from a gait file; ConfigError names file and key."""
    source = Path(path)
    data = read_toml(source)
    for key in data:
        if key not in _TOP_KEYS:
            raise ConfigError(
                source, shown_key(key), "unknown key; a gait file has gait, [params] and [meta]"
            )
    name = data.get("gait")
    if not isinstance(name, str) or name not in gait_names():
        shown = name[:100] if isinstance(name, str) else name
        problem = "missing" if name is None else f"unknown gait {shown!r}"
        raise ConfigError(source, "gait", f"{problem}; expected one of {', '.join(gait_names())}")
    raw_params = data.get("params", {})
    if not isinstance(raw_params, dict):
        raise ConfigError(source, "params", "expected a [params] table of parameter = value")
    spec = get_spec(name)
    params: dict[str, object] = {}
    for key, value in raw_params.items():
        where = f"params.{shown_key(key)}"
        if isinstance(value, bool):
            raise ConfigError(source, where, f"expected a number, got {value!r}")
        try:
            params[key] = coerce_value(name, spec.param(key), value)
        except GaitError as exc:
            raise ConfigError(source, where, str(exc)) from exc
        typed = params[key]
        numbers = typed if isinstance(typed, tuple) else (typed,)
        if any(isinstance(v, float) and abs(v) > MAX_GAIT_VALUE for v in numbers):
            raise ConfigError(
                source,
                where,
                f"expected numbers within +-{MAX_GAIT_VALUE:g} (no "
                f"angle, rate or length of a gait comes near), got {value!r}",
            )
    meta = data.get("meta", {})
    if not isinstance(meta, dict):
        raise ConfigError(source, "meta", "expected a [meta] table")
    return name, params, meta


def save_gait_file(
    path: str | Path,
    name: str,
    params: Mapping[str, object],
    meta: Mapping[str, object] | None = None,
) -> None:
    """Write a gait file that load_gait_file reads back to the same name, params and meta."""
    target = Path(path)
    spec = get_spec(name)
    lines = ["# snakebot gait file", f"gait = {_string(name)}", "", "[params]"]
    for key, value in params.items():
        param = spec.param(key)
        typed = coerce_value(name, param, value)
        unit = f"  # {param.unit}" if param.unit else ""
        lines.append(f"{_key(key)} = {_value(target, f'params.{key}', typed)}{unit}")
    if meta:
        lines += ["", "[meta]"]
        lines += [f"{_key(k)} = {_value(target, f'meta.{k}', v)}" for k, v in meta.items()]
    try:
        target.write_text("\n".join(lines) + "\n", encoding="utf-8")
    except OSError as exc:
        raise ConfigError(target, "", f"cannot write gait file: {exc.strerror or exc}") from exc


def _key(key: object) -> str:
    text = str(key)
    return text if _BARE_KEY.fullmatch(text) else _string(text)


def _string(text: str) -> str:
    escaped = (
        _ESCAPES.get(ch, f"\\u{ord(ch):04x}" if ord(ch) < 0x20 or ord(ch) == 0x7F else ch)
        for ch in text
    )
    return '"' + "".join(escaped) + '"'


def _value(path: Path, key: str, value: object) -> str:
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(float(value)) if math.isfinite(value) else str(value)
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, dt.date | dt.time):
        return value.isoformat()
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_value(path, f"{key}[{i}]", v) for i, v in enumerate(value)) + "]"
    if isinstance(value, Mapping):
        items = (f"{_key(k)} = {_value(path, f'{key}.{k}', v)}" for k, v in value.items())
        return "{ " + ", ".join(items) + " }" if value else "{}"
    raise ConfigError(path, key, f"cannot write a {type(value).__name__} to TOML")
