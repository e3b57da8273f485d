"""Descriptions of gaits and their parameters, and conversion of raw values into typed ones."""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import KW_ONLY, dataclass, field

import numpy as np

from snakebot.errors import GaitError
from snakebot.gaits.base import FloatArray, Gait
from snakebot.gaits.expr import parse_number

ParamValue = float | tuple[float, ...] | str
FLAG_UNIT = "0/1"


@dataclass(frozen=True)
class ParamSpec:
    """One gait parameter: name, unit ("rad", "rad/s", "0/1", ...), default and meaning.

    Tuning (``snakebot tune gait``): ``bounds`` is the default search range (low, high) in the
    parameter's unit, for each element of a list parameter; ``tunable`` puts the parameter in
    the gait's default search (it needs bounds). ``joint_poses`` marks a list of joint angles in
    rad, N per pose, head to tail: the tuner clips its bounds to the robot's joint limits, and
    the GA can evolve it pose by pose. Raises GaitError when these do not fit the parameter.
    """

    name: str
    unit: str
    default: float | tuple[float, ...] | str
    doc: str
    choices: tuple[str, ...] = ()
    _: KW_ONLY
    bounds: tuple[float, float] | None = None
    tunable: bool = False
    joint_poses: bool = False

    def __post_init__(self) -> None:
        where = f"parameter {self.name!r}"
        if self.bounds is not None:
            try:
                low, high = (float(v) for v in self.bounds)
            except (TypeError, ValueError):
                low = high = math.nan
            if not (self.searchable and math.isfinite(low) and math.isfinite(high) and low < high):
                raise GaitError(
                    f"{where}: bounds must be finite (low, high) with low < high, on a number or "
                    f"list parameter; got {self.bounds!r}"
                )
            object.__setattr__(self, "bounds", (low, high))
        if self.tunable and self.bounds is None:
            raise GaitError(f"{where}: a tunable parameter needs bounds (low, high)")
        if self.joint_poses and self.kind != "list":
            raise GaitError(f"{where}: joint_poses needs a list parameter")

    @property
    def searchable(self) -> bool:
        """True for number and list parameters (not text, not 0/1 flags): the tuner can move it."""
        return self.kind != "text" and self.unit != FLAG_UNIT

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


@dataclass(frozen=True)
class JointAxes:
    """The bending axis a gait needs on its even (0, 2, ...) and odd joints, counted from the
    head: "yaw", "pitch" or None (either). ``required``: on other axes the gait cannot do what
    its name says (rolling on an all-yaw snake), so it is refused rather than warned about.
    ``why`` finishes the sentence "needs ... because/for ..."."""

    even: str | None = None
    odd: str | None = None
    required: bool = False
    why: str = ""

    def mismatched(self, joint_axes: Sequence[str]) -> list[int]:
        """Indices of the joints (0 = head) whose axis is not the one this gait needs."""
        needs = (self.even, self.odd)
        return [
            i
            for i, axis in enumerate(joint_axes)
            if needs[i % 2] is not None and axis != needs[i % 2]
        ]

    def describe(self) -> str:
        """The need in words: "yaw on every joint", "yaw on even joints and pitch on odd ones"."""
        if self.even is None and self.odd is None:
            return "any axes"
        if self.even == self.odd:
            return f"{self.even} on every joint"
        parts = []
        if self.even is not None:
            parts.append(f"{self.even} on even joints (0, 2, ... from the head)")
        if self.odd is not None:
            parts.append(f"{self.odd} on odd joints")
        return " and ".join(parts)


ANY_AXES = JointAxes()


@dataclass(frozen=True)
class LiveRoles:
    """Which parameters a live driver (``snakebot drive``) moves for each of its controls.

    ``amplitude``: multiplied by the amplitude control; ``frequency``: the temporal frequencies
    (their bounds cap the speed control, which scales the phase rates); ``spatial_frequency``:
    divided by the wavelength control; ``offset``: the steering bias set by the turn control.
    Each names number parameters of the gait; an empty role falls back to a generic control
    (amplitude scales the targets, turning biases the steering joints) or none (wavelength).
    """

    amplitude: tuple[str, ...] = ()
    frequency: tuple[str, ...] = ()
    spatial_frequency: tuple[str, ...] = ()
    offset: tuple[str, ...] = ()

    def items(self) -> tuple[tuple[str, tuple[str, ...]], ...]:
        """(role, parameter names) for every role."""
        return (
            ("amplitude", self.amplitude),
            ("frequency", self.frequency),
            ("spatial_frequency", self.spatial_frequency),
            ("offset", self.offset),
        )


GaitFactory = Callable[[int, ParamValues, FloatArray, FloatArray], Gait]
TuningStart = Callable[[int, Mapping[str, object]], Mapping[str, object]]


@dataclass(frozen=True)
class GaitSpec:
    """A registered gait: its name, a one-line summary, its parameters and how to build it.

    The factory receives N, the validated values and the joint limits (N,) in rad.

    Tuning: the default search is every tunable parameter in declaration order, where each group
    in ``ties`` (e.g. both waves' temporal frequencies) moves as one value. ``tuning_start(N,
    fixed)`` gives the parameters a search starts from when the user fixed ``fixed`` (default:
    ``fixed`` itself, the rest at their defaults). ``rolls_over``: the body turns over as it
    moves, so tuning does not stop runs whose head is upside down. Raises GaitError when the
    parameters or ties do not fit together.

    ``live`` says which parameters the drive controls move (see LiveRoles).

    ``axes`` says which bending axis the gait needs on each joint (see JointAxes); a robot whose
    joints differ gets a warning, or a GaitError when ``axes.required`` (the gait cannot work).
    """

    name: str
    summary: str
    params: tuple[ParamSpec, ...]
    factory: GaitFactory = field(repr=False, compare=False)
    _: KW_ONLY
    ties: tuple[tuple[str, ...], ...] = ()
    tuning_start: TuningStart | None = field(default=None, repr=False, compare=False)
    rolls_over: bool = False
    live: LiveRoles = LiveRoles()
    axes: JointAxes = field(default_factory=lambda: ANY_AXES)

    def __post_init__(self) -> None:
        names = self.param_names
        if not isinstance(self.name, str) or not self.name or len(set(names)) != len(names):
            raise GaitError(
                f"gait {self.name!r}: expected a non-empty name and distinct parameter names, "
                f"got {', '.join(names)}"
            )
        tied: set[str] = set()
        for group in self.ties:
            params = [self.param(key) for key in group]
            if (
                len(group) < 2
                or tied & set(group)
                or any(p.kind != "number" or not p.searchable for p in params)
                or len({p.tunable for p in params}) > 1
            ):
                raise GaitError(
                    f"gait {self.name!r}: tie {'+'.join(group)} must join two or more distinct "
                    f"number parameters, all tunable or none, each in at most one tie"
                )
            tied |= set(group)
        for role, keys in self.live.items():
            if any(k not in names or self.param(k).kind != "number" for k in keys):
                raise GaitError(
                    f"gait {self.name!r}: live role {role} must name number parameters of the "
                    f"gait, got {', '.join(keys)}"
                )

    @property
    def param_names(self) -> tuple[str, ...]:
        """Parameter names in declaration order."""
        return tuple(p.name for p in self.params)

    @property
    def default_search(self) -> tuple[str, ...]:
        """What ``tune gait`` searches without --params: tunable names, ties joined by "+"."""
        out: list[str] = []
        for param in self.params:
            if param.tunable:
                group = next((g for g in self.ties if param.name in g), (param.name,))
                key = "+".join(group)
                if key not in out:
                    out.append(key)
        return tuple(out)

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
