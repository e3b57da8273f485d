"""Descriptions of gaits and their parameters, and conversion of raw values into typed ones."""

from __future__ import annotations

import difflib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from snakebot.errors import GaitError
from snakebot.gaits.base import FloatArray, Gait
from snakebot.gaits.expr import parse_number

ParamValue = float | tuple[float, ...] | str
FLAG_UNIT = "0/1"


@dataclass(frozen=True)
class ParamSpec:
    """One gait parameter: name, unit ("rad", "rad/s", "0/1", ...), default and meaning."""

    name: str
    unit: str
    default: float | tuple[float, ...] | str
    doc: str
    choices: tuple[str, ...] = ()

    @property
    def kind(self) -> str:
        """Value type: "number" (float), "list" (tuple of floats) or "text" (str)."""
        if isinstance(self.default, str):
            return "text"
        return "list" if isinstance(self.default, tuple) else "number"


@dataclass(frozen=True)
class ParamValues:
    """Validated parameter values of one gait, with typed getters for the gait factories."""

    gait: str
    values: Mapping[str, ParamValue]

    def number(self, name: str) -> float:
        """A float parameter."""
        value = self.values[name]
        assert isinstance(value, float)
        return value

    def numbers(self, name: str) -> tuple[float, ...]:
        """A list-of-floats parameter."""
        value = self.values[name]
        assert isinstance(value, tuple)
        return value

    def text(self, name: str) -> str:
        """A string parameter."""
        value = self.values[name]
        assert isinstance(value, str)
        return value

    def flag(self, name: str) -> bool:
        """A 0/1 parameter as a bool."""
        value = self.number(name)
        if value not in (0.0, 1.0):
            raise GaitError(f"{self.gait}.{name}: expected 0 or 1, got {value:g}")
        return value == 1.0


GaitFactory = Callable[[int, ParamValues, FloatArray, FloatArray], Gait]


@dataclass(frozen=True)
class GaitSpec:
    """A registered gait: its name, a one-line summary, its parameters and how to build it.

    The factory receives N, the validated values and the joint limits (N,) in rad.
    """

    name: str
    summary: str
    params: tuple[ParamSpec, ...]
    factory: GaitFactory = field(repr=False, compare=False)

    @property
    def param_names(self) -> tuple[str, ...]:
        """Parameter names in declaration order."""
        return tuple(p.name for p in self.params)

    def param(self, name: str) -> ParamSpec:
        """The parameter called name; GaitError listing the valid names otherwise."""
        for spec in self.params:
            if spec.name == name:
                return spec
        close = difflib.get_close_matches(name, self.param_names, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise GaitError(
            f"unknown parameter {name!r} for gait {self.name!r}{hint}; "
            f"valid parameters: {', '.join(self.param_names)}"
        )


def expectation(gait: str, spec: ParamSpec) -> str:
    """What a valid value looks like, e.g. "expected a number in rad/s for serpenoid.omega"."""
    where = f"{gait}.{spec.name}"
    if spec.kind == "text":
        options = ", ".join(spec.choices) if spec.choices else "text"
        return f"expected one of {options} for {where}"
    if spec.unit == FLAG_UNIT:
        return f"expected 0 or 1 for {where}"
    unit = f" in {spec.unit}" if spec.unit not in ("", "1") else ""
    if spec.kind == "list":
        return f"expected a comma-separated list of numbers{unit} for {where}"
    return f"expected a number{unit} for {where}"


def convert_value(spec: ParamSpec, value: object) -> ParamValue:
    """Convert a raw value (number, expression string, sequence) to the parameter's type.

    Raises TypeError or ValueError with the reason; callers add where the value came from.
    """
    if spec.kind == "text":
        return _to_text(spec, value)
    if spec.kind == "list":
        return _to_numbers(value)
    return _to_number(value)


def coerce_value(gait: str, spec: ParamSpec, value: object) -> ParamValue:
    """convert_value, failing with a GaitError that says what was expected and what came."""
    try:
        return convert_value(spec, value)
    except (TypeError, ValueError) as exc:
        raise GaitError(f"{expectation(gait, spec)}, got {value!r} ({exc})") from exc


def _to_number(value: object) -> float:
    if isinstance(value, str):
        return parse_number(value)
    if isinstance(value, bool | int | float | np.integer | np.floating):
        number = float(value)
        if not np.isfinite(number):
            raise ValueError("not finite")
        return number
    raise TypeError(f"{type(value).__name__} is not a number")


def _to_numbers(value: object) -> tuple[float, ...]:
    if isinstance(value, str):
        if value.strip() == "":
            return ()
        return tuple(parse_number(part) for part in value.split(","))
    if isinstance(value, np.ndarray):
        if value.ndim != 1:
            raise ValueError(f"expected a flat list, got an array of shape {value.shape}")
        value = value.tolist()
    if isinstance(value, list | tuple):
        return tuple(_to_number(item) for item in value)
    raise TypeError(f"{type(value).__name__} is not a list of numbers")


def _to_text(spec: ParamSpec, value: object) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{type(value).__name__} is not text")
    text = value.strip()
    if spec.choices and text not in spec.choices:
        raise ValueError(f"{text!r} is not a valid choice")
    return text
