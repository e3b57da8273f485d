"""The search space of a gait tuning run: which parameters move, within which bounds.

``--params omega,phase_lag`` names number parameters; ``a+b`` ties two to one value (both
temporal frequencies of a sidewinding gait); a list parameter (``poses``) contributes one
dimension per element. Without ``--params`` the gait's own default search is used, and each
parameter's declared bounds (snakebot.gaits.ParamSpec); ``--bounds omega=0.5:4*pi`` overrides
them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from snakebot.errors import ConfigError, GaitError
from snakebot.gaits import get_spec, parse_number, resolve_params
from snakebot.gaits.spec import GaitSpec, ParamValue
from snakebot.tuning.trace import FloatArray

_PI = math.pi


@dataclass(frozen=True)
class Dim:
    """One search coordinate: the parameters it sets (element ``index`` of a list) and bounds.

    ``pose_angle``: the coordinate is one joint angle of a list of joint poses (the GA crosses
    such lists over pose by pose).
    """

    name: str
    keys: tuple[str, ...]
    index: int | None
    lower: float
    upper: float
    pose_angle: bool = False


@dataclass(frozen=True)
class SearchSpace:
    """A box of D coordinates over the parameters of ``gait``; everything else stays ``base``."""

    gait: str
    base: Mapping[str, ParamValue]
    dims: tuple[Dim, ...]

    @property
    def names(self) -> tuple[str, ...]:
        """Coordinate names, e.g. ("omega", "phase_lag") or ("poses[0]", ...)."""
        return tuple(d.name for d in self.dims)

    @property
    def lower(self) -> FloatArray:
        """Lower bounds (D,)."""
        return np.array([d.lower for d in self.dims])

    @property
    def upper(self) -> FloatArray:
        """Upper bounds (D,)."""
        return np.array([d.upper for d in self.dims])

    def start(self) -> FloatArray:
        """The base parameters as a point (D,), clipped into the box."""
        values = []
        for dim in self.dims:
            value = self.base[dim.keys[0]]
            number = (
                value[dim.index] if isinstance(value, tuple) and dim.index is not None else value
            )
            values.append(float(number) if isinstance(number, float | int) else dim.lower)
        start: FloatArray = np.clip(np.array(values), self.lower, self.upper)
        return start

    def params(self, x: Sequence[float] | FloatArray) -> dict[str, ParamValue]:
        """Full gait parameters for point ``x`` (D,)."""
        out = dict(self.base)
        lists: dict[str, list[float]] = {}
        for dim, value in zip(self.dims, np.asarray(x, dtype=float).tolist(), strict=True):
            for key in dim.keys:
                if dim.index is None:
                    out[key] = value
                else:
                    lists.setdefault(key, list(_numbers(out[key])))[dim.index] = value
        out.update({key: tuple(values) for key, values in lists.items()})
        return out


def tuning_base(gait: str, joint_count: int, fixed: Mapping[str, object]) -> dict[str, ParamValue]:
    """Gait defaults with ``fixed`` (``--set``) on top, through the gait's own tuning start
    (keyframes: a mirrored half cycle, the GA report's genome)."""
    start = get_spec(gait).tuning_start
    return resolve_params(gait, start(joint_count, fixed) if start is not None else fixed)


def build_space(
    gait: str,
    base: Mapping[str, ParamValue],
    params: Sequence[str] | None = None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    joint_limit_rad: float = _PI,
) -> SearchSpace:
    """The space over ``params`` (default: the gait's default search) with ``bounds`` on top.

    ``joint_limit_rad`` caps the declared bounds of joint-pose parameters (both signs).
    """
    spec = get_spec(gait)
    names = tuple(params) if params else spec.default_search
    if not names:
        numeric = [p.name for p in spec.params if p.kind == "number"]
        raise ConfigError(
            "params",
            "",
            f"no default search parameters for {gait}; name some of: " + ", ".join(numeric),
        )
    given = dict(bounds or {})
    dims: list[Dim] = []
    used: set[str] = set()
    for name in names:
        keys = tuple(k.strip() for k in name.split("+"))
        for key in keys:
            try:
                param = spec.param(key)
            except GaitError as exc:
                raise ConfigError("params", name, str(exc)) from None
            if not param.searchable or key in used:
                raise ConfigError("params", name, "expected distinct number or list parameters")
            used.add(key)
        lower, upper = _bounds(spec, name, keys, given, joint_limit_rad)
        value = base[keys[0]]
        if isinstance(value, tuple):
            if len(keys) > 1 or not value:
                raise ConfigError("params", name, "a list parameter cannot be tied or empty")
            poses = spec.param(keys[0]).joint_poses
            dims += [Dim(f"{name}[{i}]", keys, i, lower, upper, poses) for i in range(len(value))]
        else:
            dims.append(Dim(name, keys, None, lower, upper))
    unknown = set(given) - {d.name for d in dims} - used
    if unknown:
        raise ConfigError("bounds", sorted(unknown)[0], "not one of the searched parameters")
    return SearchSpace(gait, dict(base), tuple(dims))


def parse_bounds(items: Sequence[str]) -> dict[str, tuple[float, float]]:
    """``name=LOW:HIGH`` items (comma-separated or repeated); numbers may be "pi/4"."""
    out: dict[str, tuple[float, float]] = {}
    for item in (part for text in items for part in text.split(",") if part.strip()):
        name, sep, rest = item.partition("=")
        low, colon, high = rest.partition(":")
        try:
            if not (sep and colon):
                raise ValueError("missing = or :")
            lower, upper = parse_number(low), parse_number(high)
        except ValueError as exc:
            raise ConfigError(
                "bounds", item, f"expected NAME=LOW:HIGH, e.g. omega=0.5:4*pi ({exc})"
            ) from None
        if not lower < upper:
            raise ConfigError("bounds", item, "expected LOW < HIGH")
        out[name.strip()] = (lower, upper)
    return out


def _bounds(
    spec: GaitSpec,
    name: str,
    keys: tuple[str, ...],
    given: Mapping[str, tuple[float, float]],
    limit: float,
) -> tuple[float, float]:
    for key in (name, *keys):
        if key in given:
            return given[key]
    param = spec.param(keys[0])
    if param.bounds is None:
        raise ConfigError("bounds", name, f"no default bounds; give bounds {name}=LOW:HIGH")
    lower, upper = param.bounds
    if param.joint_poses:
        lower, upper = max(lower, -limit), min(upper, limit)
    return lower, upper


def _numbers(value: ParamValue) -> tuple[float, ...]:
    return value if isinstance(value, tuple) else ()
