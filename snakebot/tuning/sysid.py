"""Fit the twin's servo parameters to telemetry logs (``snakebot sysid``).

Each log's commands are replayed open loop on twins that differ only in the fitted parameters,
side by side (engine.TwinBatch), from the pose the log starts in. The residual is the joint
positions (rad) and, weighted by ``VELOCITY_WEIGHT_S``, velocities of twin minus log.
``scipy.optimize.least_squares`` (trust-region reflective, box bounds, Jacobian scaling) fits the
logarithms of the parameters relative to the current ones, but the actuator delay in seconds
within [0, MAX_ACTUATOR_DELAY_S]; the finite-difference Jacobian is one parallel batch.
(``mujoco.minimize``'s Levenberg-Marquardt stalled on the armature, whose effect is some 50 times
weaker than the stiffness's; the scaled trust region does not.) The delay often starts on its
bound 0 and may end there, where the reflective method's scaling (by the distance to the bound)
freezes it: with the delay, the fit uses the rectangular trust region ("dogbox") instead.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from scipy.optimize import least_squares

from snakebot.backends.twin import TwinBackend
from snakebot.config.schema import MAX_ACTUATOR_DELAY_S, RobotConfig
from snakebot.errors import ConfigError
from snakebot.servo.dynamics import servo_dynamics
from snakebot.telemetry import read_log
from snakebot.tuning.commands import ArrayCommands
from snakebot.tuning.engine import TwinBatch
from snakebot.tuning.trace import FloatArray

PARAMS = ("stiffness", "damping", "armature", "friction_loss", "delay", "p_divisor")
DEFAULT_PARAMS = ("stiffness", "damping", "armature")
# Where each parameter lives in ServoFit and in the robot file's [twin.servo].
FIELDS = {
    "stiffness": "stiffness_scale",
    "damping": "damping_nms",
    "armature": "armature_kgm2",
    "friction_loss": "friction_loss_nm",
    "delay": "actuator_delay_s",
    "p_divisor": "p_gain_divisor",
}
VELOCITY_WEIGHT_S = 0.05
SEARCH_FACTOR = 5.0  # each parameter is searched within [current / 5, current * 5]
# Contacts and friction make the replay rough at small scales: difference over 2 % changes.
FD_STEP = 0.02
# The delayed command is piecewise linear in the delay between timesteps (2 ms on the shipped
# robots): a 1 ms step spans at most one kink.
FD_DELAY_STEP_S = 0.001


@dataclass(frozen=True)
class ServoFit:
    """The fitted servo parameters as the robot file's ``[twin.servo]`` holds them.

    ``actuator_delay_s`` None: the twin has no delay model (and no command history).
    ``p_gain_divisor``: the servo's gain mapping's P divisor (snakebot.servo.GainMapping; 256
    bam's XL330, 128 the e-Manual); fitting it alone says which holds for your servo, fitting it
    with ``stiffness`` is degenerate (both scale the same stiffness).
    """

    stiffness_scale: float
    damping_nms: float
    armature_kgm2: float
    friction_loss_nm: float
    p_gain_divisor: float
    actuator_delay_s: float | None = None

    @classmethod
    def of(cls, robot: RobotConfig) -> ServoFit:
        """The values the robot's twin uses now."""
        physics = robot.servo.physics
        servo = servo_dynamics(physics, robot.gains)
        return cls(
            physics.stiffness_scale,
            servo.joint_damping_nms,
            servo.armature_kgm2,
            servo.friction_loss_nm,
            physics.p_gain_divisor,
            physics.actuator_delay_s,
        )

    def apply(self, robot: RobotConfig) -> RobotConfig:
        """``robot`` with these servo parameters, as if written to its ``[twin.servo]``.

        Another ``p_gain_divisor`` keeps the gain registers the robot's servos hold (those the
        log was recorded with) and gives the SI gains they mean under the new mapping.
        """
        physics = dataclasses.replace(
            robot.servo.physics,
            stiffness_scale=self.stiffness_scale,
            damping_nms=self.damping_nms,
            armature_kgm2=self.armature_kgm2,
            friction_loss_nm=self.friction_loss_nm,
            actuator_delay_s=self.actuator_delay_s,
            p_gain_divisor=self.p_gain_divisor,
        )
        servo = dataclasses.replace(robot.servo, physics=physics)
        gains = robot.gains
        if physics.p_gain_divisor != robot.servo.physics.p_gain_divisor:
            gains = servo.gains_from(robot.gain_writes)
        return dataclasses.replace(robot, servo=servo, gains=gains)

    def scaled(self, names: Sequence[str], factors: Sequence[float]) -> ServoFit:
        """These values with parameter ``names[i]`` multiplied by ``factors[i]``; ``delay`` is
        not a factor but the new delay (s)."""
        fields = dict(zip(names, factors, strict=True))
        return ServoFit(
            self.stiffness_scale * fields.get("stiffness", 1.0),
            self.damping_nms * fields.get("damping", 1.0),
            self.armature_kgm2 * fields.get("armature", 1.0),
            self.friction_loss_nm * fields.get("friction_loss", 1.0),
            self.p_gain_divisor * fields.get("p_divisor", 1.0),
            fields.get("delay", self.actuator_delay_s),
        )

    def at(self, names: Sequence[str], x: Sequence[float]) -> ServoFit:
        """The fit's point ``x``: log factors on these values, but ``delay`` in seconds."""
        values = [v if n == "delay" else math.exp(v) for n, v in zip(names, x, strict=True)]
        return self.scaled(names, values)

    def report(self, robot: RobotConfig) -> dict[str, float]:
        """JSON-ready values, with the stiffness also in N·m/rad at the robot's gains."""
        fitted = self.apply(robot)
        servo = servo_dynamics(fitted.servo.physics, fitted.gains)
        return {
            "stiffness_scale": self.stiffness_scale,
            "stiffness_nm_per_rad": servo.stiffness_nm_per_rad,
            "damping_nms": self.damping_nms,
            "armature_kgm2": self.armature_kgm2,
            "friction_loss_nm": self.friction_loss_nm,
            "actuator_delay_s": self.actuator_delay_s or 0.0,
            "p_gain_divisor": self.p_gain_divisor,
        }


@dataclass(frozen=True)
class LogData:
    """One telemetry log: control period (s), commands, positions, velocities (K, N)."""

    path: Path
    dt_s: float
    command_rad: FloatArray
    position_rad: FloatArray
    velocity_rad_s: FloatArray

    @property
    def start_pose_rad(self) -> FloatArray:
        """The pose one control period before the first row (first-order estimate)."""
        start: FloatArray = self.position_rad[0] - self.velocity_rad_s[0] * self.dt_s
        return start


def load_log(path: Path, robot: RobotConfig) -> LogData:
    """Read a telemetry CSV of ``robot``; ConfigError when it does not fit."""
    log = read_log(path)
    command = log.joints("command_rad")
    if command.shape[1] != robot.joint_count or len(command) < 10:
        raise ConfigError(
            path,
            "",
            f"expected a log of {robot.joint_count} joints with at least 10 rows, "
            f"got {command.shape[1]} joints and {len(command)} rows",
        )
    steps = np.diff(log.column("time_s"))
    dt = float(np.median(steps)) if steps.size else 0.01
    return LogData(path, dt, command, log.joints("position_rad"), log.joints("velocity_rad_s"))


@dataclass(frozen=True)
class SysidResult:
    """Parameters before and after, the twin-vs-log position RMS (rad) for each, the number of
    log replays the fit took, and the replays (positions then velocities, (2K, N)) per log."""

    names: tuple[str, ...]
    before: ServoFit
    after: ServoFit
    rms_before_rad: float
    rms_after_rad: float
    simulations: int
    replay_before: tuple[FloatArray, ...]
    replay_after: tuple[FloatArray, ...]


class Replayer:
    """Replays logs on twins of ``robot`` with other servo parameters, ``workers`` at a time."""

    def __init__(self, robot: RobotConfig, logs: Sequence[LogData], workers: int = 2) -> None:
        self.robot, self.logs = robot, list(logs)
        self.batch = TwinBatch(robot, workers=workers)
        self.runs = 0
        for log in self.logs:
            self.batch.twin.steps_for(log.dt_s)  # a rate the twin can run, or ConfigError

    def positions(self, fits: Sequence[ServoFit]) -> list[list[FloatArray]]:
        """Per fit, per log: the twin's joint positions (K, N) under the log's commands."""
        models = [_model(fit.apply(self.robot)) for fit in fits]
        out: list[list[FloatArray]] = [[] for _ in fits]
        for log in self.logs:
            cycles = len(log.command_rad)
            commands = ArrayCommands(
                np.broadcast_to(log.command_rad, (len(fits), *log.command_rad.shape))
            )
            # The servos held the log's first goal before it began (at rest, under load).
            start = self.batch.initial_state_with_pose(log.start_pose_rad, log.command_rad[0])
            traces = self.batch.run(
                commands, cycles * log.dt_s, 1.0 / log.dt_s, models=models, initial_state=start
            )
            for i, trace in enumerate(traces):
                out[i].append(np.vstack([trace.position_rad, trace.velocity_rad_s]))
        self.runs += len(fits)
        return out

    def residuals(self, fits: Sequence[ServoFit]) -> FloatArray:
        """(M, len(fits)): position and weighted velocity errors of every log, stacked."""
        columns = []
        for replays in self.positions(fits):
            parts = []
            for log, both in zip(self.logs, replays, strict=True):
                k = len(log.command_rad)
                position, velocity = both[:k], both[k:]
                if position.shape != log.position_rad.shape:  # a diverged replay
                    position = np.full_like(log.position_rad, 10.0)
                    velocity = np.zeros_like(log.velocity_rad_s)
                parts.append((position - log.position_rad).ravel())
                parts.append(VELOCITY_WEIGHT_S * (velocity - log.velocity_rad_s).ravel())
            columns.append(np.concatenate(parts))
        return np.stack(columns, axis=1)


def fit_servo(
    robot: RobotConfig,
    logs: Sequence[LogData],
    names: Sequence[str] = DEFAULT_PARAMS,
    *,
    workers: int = 2,
    max_evaluations: int = 40,
) -> SysidResult:
    """Fit ``names`` (some of PARAMS) so the twin replays ``logs`` as the robot did.

    Fitting ``delay`` gives every candidate twin a command history (a robot without a delay
    model starts from 0 s), so all of them share one layout and one batch.
    """
    names = tuple(names)
    unknown = [n for n in names if n not in PARAMS]
    if unknown or not names:
        raise ConfigError("params", ",".join(unknown), f"expected some of {', '.join(PARAMS)}")
    start = ServoFit.of(robot)
    zero = [n for n in names if n != "delay" and getattr(start, FIELDS[n]) <= 0]
    if zero:
        raise ConfigError("params", zero[0], "cannot fit a parameter that is 0 now (log scale)")
    if "delay" in names and start.actuator_delay_s is None:
        start = dataclasses.replace(start, actuator_delay_s=0.0)
        robot = start.apply(robot)
    replayer = Replayer(robot, logs, workers)
    bound = math.log(SEARCH_FACTOR)
    is_delay = np.array([n == "delay" for n in names])
    lower = np.where(is_delay, 0.0, -bound)
    upper = np.where(is_delay, MAX_ACTUATOR_DELAY_S, bound)
    step = np.where(is_delay, FD_DELAY_STEP_S, FD_STEP)
    x0 = np.where(is_delay, start.actuator_delay_s or 0.0, 0.0)
    last: dict[bytes, FloatArray] = {}

    def residuals(points: Sequence[FloatArray]) -> FloatArray:
        return replayer.residuals([start.at(names, p.tolist()) for p in points])

    def residual(x: FloatArray) -> FloatArray:
        r = last.get(x.tobytes())
        if r is None:
            last.clear()
            r = last[x.tobytes()] = residuals([x])[:, 0]
        return r

    def jacobian(x: FloatArray) -> FloatArray:
        # Central differences: forward ones stopped ~10 % short on the weak armature direction.
        low = np.maximum(x - step, lower)
        high = np.minimum(x + step, upper)
        eye = np.eye(len(x))
        points = [x + (h - x) * e for h, e in zip(high, eye, strict=True)]
        points += [x + (lo - x) * e for lo, e in zip(low, eye, strict=True)]
        shifted = residuals(points)
        n = len(x)
        jac: FloatArray = (shifted[:, :n] - shifted[:, n:]) / (high - low)
        return jac

    solution = least_squares(
        residual,
        x0,
        jac=jacobian,
        bounds=(lower, upper),
        method="dogbox" if "delay" in names else "trf",
        x_scale="jac",
        max_nfev=max_evaluations,
    )
    after = start.at(names, solution.x.tolist())
    replays = replayer.positions([start, after])
    return SysidResult(
        names,
        start,
        after,
        _position_rms(logs, replays[0]),
        _position_rms(logs, replays[1]),
        replayer.runs,
        tuple(r[: len(log.command_rad)] for r, log in zip(replays[0], logs, strict=True)),
        tuple(r[: len(log.command_rad)] for r, log in zip(replays[1], logs, strict=True)),
    )


def _model(robot: RobotConfig) -> mujoco.MjModel:
    twin = TwinBackend(robot)
    twin.connect()
    try:
        return copy.copy(twin.model)  # before close() may turn torque off in it
    finally:
        twin.close()


def _position_rms(logs: Sequence[LogData], replays: Sequence[FloatArray]) -> float:
    errors = [
        (both[: len(log.command_rad)] - log.position_rad).ravel()
        for log, both in zip(logs, replays, strict=True)
        if both[: len(log.command_rad)].shape == log.position_rad.shape
    ]
    return float(np.sqrt(np.mean(np.square(np.concatenate(errors))))) if errors else math.nan
