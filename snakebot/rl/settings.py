"""Settings of the learning environments: frozen, JSON-ready, saved with every trained policy."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from snakebot.errors import ConfigError
from snakebot.rl.encodings import ENCODINGS

GOAL_ENV_ID = "snakebot/SnakeGoal-v0"
VELOCITY_ENV_ID = "snakebot/SnakeVelocity-v0"
ENV_IDS = (GOAL_ENV_ID, VELOCITY_ENV_ID)
GOAL_ORIGINS = ("com", "head")
# The largest clock settings that make sense for a twin episode: beyond them a policy folder (or a
# --set) would ask for a day of simulation per episode or a step no servo can follow.
MOST = {"action_hz": 1000.0, "control_hz": 10_000.0, "episode_s": 86_400.0, "phase_hz": 100.0}


@dataclass(frozen=True)
class EnvSettings:
    """What both tasks share: the robot, the encoding and the clocks.

    ``action_hz``: how often the policy acts; ``control_hz``: the gait -> safety -> backend
    cycle in between (a whole multiple of ``action_hz``, and a whole number of physics steps);
    ``episode_s``: episodes end (truncated) after this much simulated time; ``phase_hz``: the
    dft_shift wave's laps per second and the clock of static encodings; ``dft_bins``: K;
    ``timestep_s``: overrides the robot's twin timestep; ``terrain``: the twin's ground,
    ``NAME[:key=value,...]`` as ``snakebot run --terrain`` takes it (docs/terrain.md);
    ``friction_model``: auto, pairs or scale (None: the robot file's).
    """

    robot: str = "snake8"
    encoding: str = "dft_shift"
    action_hz: float = 10.0
    control_hz: float = 50.0
    episode_s: float = 30.0
    phase_hz: float = 0.5
    dft_bins: int = 3
    timestep_s: float | None = None
    terrain: str = "flat"
    friction_model: str | None = None

    def __post_init__(self) -> None:
        for key in ("robot", "terrain"):
            if not isinstance(getattr(self, key), str):
                raise ConfigError(key, "", f"expected a name (text), got {getattr(self, key)!r}")
        if self.encoding not in ENCODINGS:
            raise ConfigError(
                "encoding",
                "",
                f"unknown encoding {self.encoding!r}; expected one of {', '.join(ENCODINGS)}",
            )
        if self.friction_model is not None and not isinstance(self.friction_model, str):
            raise ConfigError(
                "friction_model",
                "",
                f"expected auto, pairs, scale or null, got {self.friction_model!r}",
            )
        for key, most in MOST.items():
            _positive(key, getattr(self, key), most)
        if self.timestep_s is not None:
            _positive("timestep_s", self.timestep_s, 0.1)
            if self.timestep_s < 1e-5:  # 100,000 physics steps per simulated second at most
                raise ConfigError(
                    "timestep_s", "", f"expected at least 1e-05 s, got {self.timestep_s!r}"
                )
        if isinstance(self.dft_bins, bool) or not isinstance(self.dft_bins, int):
            raise ConfigError("dft_bins", "", f"expected a whole number, got {self.dft_bins!r}")
        ratio = self.control_hz / self.action_hz
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ConfigError(
                "control_hz",
                "",
                f"expected a whole multiple of action_hz "
                f"{self.action_hz:g} Hz, got {self.control_hz:g} Hz",
            )

    @property
    def cycles_per_action(self) -> int:
        """Control cycles per policy action."""
        return round(self.control_hz / self.action_hz)

    @property
    def max_steps(self) -> int:
        """Policy steps in one episode."""
        return max(1, round(self.episode_s * self.action_hz))


@dataclass(frozen=True)
class GoalSettings:
    """The goal task: where goals appear and what the reward pays.

    Goals appear ``goal_distance_bl`` (low, high) body lengths from ``goal_from`` ("com": the
    centre of mass; "head": the head module, as the seed measures), or ``goal_distance_m`` (low,
    high) metres when that is set (the seed's 5-7 m; None: body lengths), at a bearing in
    ``goal_bearing_rad`` (low, high) from the snake's starting heading (default: all around).
    Reward per step = -step_cost + velocity_weight * (COM velocity toward the goal, body
    lengths/s) - distance_weight * (distance, body lengths) + goal_bonus on reaching the goal
    (within ``goal_radius_bl``), which ends the episode.
    """

    goal_distance_bl: tuple[float, float] = (2.0, 4.0)
    goal_distance_m: tuple[float, float] | None = None
    goal_from: str = "com"
    goal_bearing_rad: tuple[float, float] = (-math.pi, math.pi)
    goal_radius_bl: float = 0.5
    step_cost: float = 0.01
    velocity_weight: float = 1.0
    distance_weight: float = 0.01
    goal_bonus: float = 10.0

    def __post_init__(self) -> None:
        if self.goal_from not in GOAL_ORIGINS:
            expected = ", ".join(GOAL_ORIGINS)
            raise ConfigError("goal_from", "", f"expected {expected}, got {self.goal_from!r}")
        _finite_fields(self, skip=("goal_from", "goal_distance_m"))
        _range("goal_distance_bl", self.goal_distance_bl, 0.0)
        if self.goal_distance_m is not None:
            _range("goal_distance_m", self.goal_distance_m, 0.0)
        _range("goal_bearing_rad", self.goal_bearing_rad, -math.inf)
        _positive("goal_radius_bl", self.goal_radius_bl)


@dataclass(frozen=True)
class VelocitySettings:
    """The velocity task: commands (speed m/s along the body, turn rate rad/s), resampled every
    ``command_period_s``; reward = exp(-(v - v_cmd)^2 / speed_sigma^2) + turn_weight *
    exp(-(w - w_cmd)^2 / turn_sigma^2) - effort_weight * mean (effort / stall torque)^2."""

    speed_range_mps: tuple[float, float] = (0.05, 0.35)
    turn_range_rad_s: tuple[float, float] = (-0.3, 0.3)
    command_period_s: float = 5.0
    speed_sigma_mps: float = 0.1
    turn_sigma_rad_s: float = 0.15
    turn_weight: float = 0.5
    effort_weight: float = 0.05

    def __post_init__(self) -> None:
        _finite_fields(self)
        _range("speed_range_mps", self.speed_range_mps, -math.inf)
        _range("turn_range_rad_s", self.turn_range_rad_s, -math.inf)
        _positive("command_period_s", self.command_period_s, 1e9)  # 1e9: one command (eval)
        for key in ("speed_sigma_mps", "turn_sigma_rad_s"):
            _positive(key, getattr(self, key))


def _positive(key: str, value: object, most: float = math.inf) -> None:
    if (
        isinstance(value, bool)
        or not isinstance(value, int | float)
        or not (0 < value <= most and math.isfinite(value))
    ):
        bound = "" if math.isinf(most) else f" up to {most:g}"
        raise ConfigError(key, "", f"expected a positive number{bound}, got {value!r}")


def _finite_fields(settings: object, skip: tuple[str, ...] = ()) -> None:
    """ConfigError naming the first field (but those in ``skip``, checked by their owner) that is
    not a finite number (or pair of them)."""
    for item in dataclasses.fields(settings):  # type: ignore[arg-type]
        if item.name in skip:
            continue
        value = getattr(settings, item.name)
        values = value if isinstance(value, tuple | list) else (value,)
        if not all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            for v in values
        ):
            raise ConfigError(item.name, "", f"expected a finite number, got {value!r}")


def _range(key: str, value: object, minimum: float) -> None:
    ok = isinstance(value, tuple | list) and len(value) == 2
    if ok:
        assert isinstance(value, tuple | list)
        try:
            low, high = (float(v) for v in value)
        except (TypeError, ValueError):
            low = high = math.nan
        ok = math.isfinite(low) and math.isfinite(high) and minimum <= low <= high
    if not ok:
        raise ConfigError(
            key, "", f"expected (low, high) with {minimum:g} <= low <= high, got {value!r}"
        )


def split_kwargs(kwargs: dict[str, Any], *task: type) -> tuple[Any, ...]:
    """Sort env kwargs into EnvSettings and the task's settings classes; ConfigError naming an
    unknown key and listing the valid ones."""
    classes = (EnvSettings, *task)
    known = {f.name: cls for cls in classes for f in dataclasses.fields(cls)}
    unknown = sorted(set(kwargs) - set(known))
    if unknown:
        raise ConfigError(
            unknown[0], "", f"unknown env setting; expected one of {', '.join(sorted(known))}"
        )
    out = []
    for cls in classes:
        mine = {k: _tuple(v) for k, v in kwargs.items() if known[k] is cls}
        out.append(cls(**mine))
    return tuple(out)


def _tuple(value: object) -> object:
    return tuple(value) if isinstance(value, list) else value


def settings_dict(*settings: object) -> dict[str, Any]:
    """All fields of the given settings dataclasses as one JSON-ready dict."""
    out: dict[str, Any] = {}
    for item in settings:
        out.update(dataclasses.asdict(item))  # type: ignore[call-overload]
    return out


__all__ = [
    "ENV_IDS",
    "GOAL_ENV_ID",
    "GOAL_ORIGINS",
    "MOST",
    "VELOCITY_ENV_ID",
    "EnvSettings",
    "GoalSettings",
    "VelocitySettings",
    "settings_dict",
    "split_kwargs",
]
