"""The search space of a gait tuning run: which parameters move, within which bounds.

``--params omega,phase_lag`` names number parameters; ``a+b`` ties two to one value (both
temporal frequencies of a sidewinding gait); a list parameter (``poses``) contributes one
dimension per element. ``--bounds omega=0.5:4*pi`` overrides the defaults below.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from snakebot.errors import ConfigError, GaitError
from snakebot.gaits import get_spec, parse_number, resolve_params
from snakebot.gaits.keyframes import default_poses
from snakebot.gaits.spec import ParamValue
from snakebot.tuning.trace import FloatArray

_SIDEWINDING = (
    "amplitude_even",
    "amplitude_odd",
    "spatial_freq_even+spatial_freq_odd",
    "temporal_freq_even+temporal_freq_odd",
    "phase_shift",
)
DEFAULT_PARAMS: dict[str, tuple[str, ...]] = {
    "serpenoid": ("omega", "phase_lag"),
    "compound": _SIDEWINDING,
    "sidewinding": _SIDEWINDING,
    "lateral_undulation": (
        "amplitude_even",
        "spatial_freq_even+spatial_freq_odd",
        "temporal_freq_even+temporal_freq_odd",
    ),
    "keyframes": ("poses",),
}
_PI = math.pi
# Frequencies reach 3 Hz, past what the servos can play at useful amplitudes: the envelope (the
# servo's speed), not the box, should decide how fast a gait can go.
DEFAULT_BOUNDS: dict[str, tuple[float, float]] = {
    "amplitude": (0.05, 1.2),
    "amplitude_even": (0.05, 1.2),
    "amplitude_odd": (0.05, 1.2),
    "omega": (0.5, 6 * _PI),
    "temporal_freq_even": (0.5, 6 * _PI),
    "temporal_freq_odd": (0.5, 6 * _PI),
    "phase_lag": (0.1, _PI / 2),
    "spatial_freq_even": (0.1, _PI / 2),
    "spatial_freq_odd": (0.1, _PI / 2),
    "phase_shift": (-_PI, _PI),
    "offset": (-0.3, 0.3),
    "offset_even": (-0.3, 0.3),
    "offset_odd": (-0.3, 0.3),
    "poses": (-_PI / 4, _PI / 4),
    "durations": (0.2, 1.5),
}


@dataclass(frozen=True)
class Dim:
    """One search coordinate: the parameters it sets (element ``index`` of a list) and bounds."""

    name: str
    keys: tuple[str, ...]
    index: int | None
    lower: float
    upper: float


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
    """Gait defaults with ``fixed`` (``--set``) on top; keyframes default to a mirrored half cycle.

    The GA report's genome is half a cycle mirrored: the first two of the default four S-curve
    poses, mirrored, give the same four keyframes and half the genes.
    """
    params = dict(fixed)
    if gait == "keyframes" and "poses" not in params:
        params["poses"] = default_poses(joint_count)[: 2 * joint_count]
        params.setdefault("mirror", 1.0)
    return resolve_params(gait, params)


def build_space(
    gait: str,
    base: Mapping[str, ParamValue],
    params: Sequence[str] | None = None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    joint_limit_rad: float = _PI,
) -> SearchSpace:
    """The space over ``params`` (default: DEFAULT_PARAMS of the gait) with ``bounds`` on top."""
    spec = get_spec(gait)
    names = tuple(params) if params else DEFAULT_PARAMS.get(gait, ())
    if not names:
        numeric = [p.name for p in spec.params if p.kind == "number"]
        raise ConfigError(
            "--params",
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
                raise ConfigError("--params", name, str(exc)) from None
            if param.kind == "text" or param.unit == "0/1" or key in used:
                raise ConfigError("--params", name, "expected distinct number or list parameters")
            used.add(key)
        lower, upper = _bounds(name, keys, given, joint_limit_rad)
        value = base[keys[0]]
        if isinstance(value, tuple):
            if len(keys) > 1 or not value:
                raise ConfigError("--params", name, "a list parameter cannot be tied or empty")
            dims += [Dim(f"{name}[{i}]", keys, i, lower, upper) for i in range(len(value))]
        else:
            dims.append(Dim(name, keys, None, lower, upper))
    unknown = set(given) - {d.name for d in dims} - used
    if unknown:
        raise ConfigError("--bounds", sorted(unknown)[0], "not one of the searched parameters")
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
                "--bounds", item, f"expected NAME=LOW:HIGH, e.g. omega=0.5:4*pi ({exc})"
            ) from None
        if not lower < upper:
            raise ConfigError("--bounds", item, "expected LOW < HIGH")
        out[name.strip()] = (lower, upper)
    return out


def _bounds(
    name: str, keys: tuple[str, ...], given: Mapping[str, tuple[float, float]], limit: float
) -> tuple[float, float]:
    for key in (name, *keys):
        if key in given:
            return given[key]
    if keys[0] not in DEFAULT_BOUNDS:
        raise ConfigError("--bounds", name, f"no default bounds; pass --bounds {name}=LOW:HIGH")
    lower, upper = DEFAULT_BOUNDS[keys[0]]
    if keys[0] == "poses":
        lower, upper = max(lower, -limit), min(upper, limit)
    return lower, upper


def _numbers(value: ParamValue) -> tuple[float, ...]:
    return value if isinstance(value, tuple) else ()
