"""Every gait by name: specs for --help, make_gait() for the runner, key=value parsing.

Gaits come from the built-ins below, from installed plugins (entry-point group
``snakebot.gaits``, each entry naming a GaitSpec) and from register_gait(); the clash and
failure rules are snakebot.plugins'.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence

import numpy as np
import numpy.typing as npt

from snakebot.errors import GaitAxesWarning, GaitError, GaitParamError
from snakebot.gaits import cmu, compound, dft, keyframes, miller, serpenoid, simple
from snakebot.gaits.base import FloatArray, Gait, check_joint_count
from snakebot.gaits.spec import (
    GaitSpec,
    ParamSpec,
    ParamValue,
    ParamValues,
    coerce_value,
    convert_value,
    expectation,
)
from snakebot.plugins import Origin, Registry

__all__ = [
    "GAITS",
    "GaitSpec",
    "ParamSpec",
    "gait_names",
    "gait_origin",
    "get_spec",
    "make_gait",
    "parse_set_options",
    "register_gait",
    "resolve_params",
]

DEFAULT_LIMIT_RAD = math.pi / 2
ENTRY_POINT_GROUP = "snakebot.gaits"


def _check_spec(name: str, obj: object) -> GaitSpec:
    if not isinstance(obj, GaitSpec):
        raise TypeError(f"expected a snakebot.gaits.GaitSpec, got {type(obj).__name__}")
    if obj.name != name:
        raise ValueError(f"its GaitSpec is named {obj.name!r}; the names must match")
    return obj


GAITS: Registry[GaitSpec] = Registry(
    "gait",
    ENTRY_POINT_GROUP,
    error=GaitError,
    check=_check_spec,
    builtins={
        spec.name: spec
        for spec in (
            serpenoid.SPEC,
            *compound.SPECS,
            *dft.SPECS,
            simple.SPEC,
            keyframes.SPEC,
            *miller.SPECS,
            *cmu.SPECS,
        )
    },
)


def register_gait(spec: GaitSpec, *, replace: bool = False) -> None:
    """Make gait ``spec.name`` available to make_gait, the CLI and the tuner in this process.

    Raises GaitError when the name is taken (a built-in, a plugin or an earlier registration)
    and ``replace`` is false; GAITS.unregister(name) undoes a registration.
    """
    if not isinstance(spec, GaitSpec):
        raise GaitError(f"register_gait expects a GaitSpec, got {type(spec).__name__}")
    GAITS.register(spec.name, spec, replace=replace)


def gait_names() -> list[str]:
    """Names of all registered gaits, sorted (plugins included, even ones not imported yet)."""
    return GAITS.names()


def get_spec(name: str) -> GaitSpec:
    """The spec of gait name; GaitError listing the known gaits otherwise, or saying why a
    plugin's gait could not be loaded."""
    return GAITS.get(name)


def gait_origin(name: str) -> Origin:
    """Where gait name comes from: built-in, a plugin (distribution, version) or runtime."""
    return GAITS.origin(name)


def resolve_params(name: str, params: Mapping[str, object] | None = None) -> dict[str, ParamValue]:
    """Defaults of gait name overlaid with params, each converted to its declared type."""
    spec = get_spec(name)
    given = dict(params or {})
    for key in given:
        if not isinstance(key, str):
            raise GaitError(f"{name}: parameter names must be strings, got {key!r}")
        spec.param(key)
    return {
        p.name: coerce_value(name, p, given[p.name]) if p.name in given else p.default
        for p in spec.params
    }


def make_gait(
    name: str,
    joint_count: int,
    params: Mapping[str, object] | None = None,
    *,
    lower_rad: npt.ArrayLike | None = None,
    upper_rad: npt.ArrayLike | None = None,
) -> Gait:
    """Build gait name for N joints; limits (N,) in rad default to +-pi/2 (dft gaits use them)."""
    spec = get_spec(name)
    n = check_joint_count(name, joint_count)
    values = ParamValues(name, resolve_params(name, params))
    lower = _limit(name, "lower_rad", lower_rad, n, -DEFAULT_LIMIT_RAD)
    upper = _limit(name, "upper_rad", upper_rad, n, DEFAULT_LIMIT_RAD)
    if np.any(lower > upper):
        raise GaitError(f"{name}: expected lower_rad <= upper_rad for every joint")
    return spec.factory(n, values, lower, upper)


def check_joint_axes(name: str, joint_axes: Sequence[str], robot: str = "the robot") -> str | None:
    """Whether gait ``name`` fits a robot whose joints bend about ``joint_axes`` (head first).

    Returns None when it fits; else warns (GaitAxesWarning) naming the joints that differ and
    returns the text. Raises GaitError instead when the gait declares the axes required (it
    cannot work there).
    """
    need = get_spec(name).axes
    wrong = need.mismatched(joint_axes)
    if not wrong:
        return None
    joints = ", ".join(f"{i} ({joint_axes[i]})" for i in wrong[:6])
    joints += " ..." if len(wrong) > 6 else ""
    text = (
        f"gait {name!r} needs {need.describe()}{': ' + need.why if need.why else ''}; "
        f"{robot} has other axes on joints {joints}"
    )
    if need.required:
        raise GaitError(f"{text}. Pick a gait made for these axes (`snakebot gaits`)")
    text += f", so it will not move as the name {name!r} says"
    warnings.warn(text, GaitAxesWarning, stacklevel=2)
    return text


def parse_set_options(name: str, items: Sequence[str], *, source: str = "set") -> dict[str, object]:
    """Parse ``"key=value"`` strings for gait ``name`` into typed values (numbers may be
    ``"pi/4"``). GaitParamError (source ``source``, key the offending text) for a malformed
    item, an unknown key or a value of the wrong kind."""
    spec = get_spec(name)
    parsed: dict[str, object] = {}
    for item in items:
        key, sep, raw = str(item).partition("=")
        key = key.strip()
        if not sep or not key:
            raise GaitParamError(
                source,
                str(item),
                f"expected key=value, e.g. {_example(spec.params[0])}; "
                f"valid keys for {name}: {', '.join(spec.param_names)}",
            )
        try:
            param = spec.param(key)
        except GaitError as exc:
            raise GaitParamError(source, str(item), str(exc)) from None
        try:
            parsed[key] = convert_value(param, raw)
        except (TypeError, ValueError) as exc:
            raise GaitParamError(source, str(item), f"{expectation(name, param)} ({exc})") from None
    return parsed


def _example(param: ParamSpec) -> str:
    default = param.default
    if isinstance(default, tuple):
        return f"{param.name}={','.join(f'{v:g}' for v in default) or '0.1,0.2'}"
    return f"{param.name}={default:g}" if isinstance(default, float) else f"{param.name}={default}"


def _limit(
    name: str, key: str, values: npt.ArrayLike | None, joint_count: int, default: float
) -> FloatArray:
    if values is None:
        return np.full(joint_count, default)
    try:
        limit = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise GaitError(f"{name}: {key} must be {joint_count} numbers in rad ({exc})") from exc
    if limit.shape != (joint_count,) or not np.all(np.isfinite(limit)):
        raise GaitError(
            f"{name}: {key} must be {joint_count} finite numbers in rad (one per joint), "
            f"got shape {limit.shape}"
        )
    return limit
