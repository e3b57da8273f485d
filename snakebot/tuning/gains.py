"""Servo gain tuning on any Backend: step tests one joint at a time, then a reference gait.

The same code drives the twin and the servo chain. Candidates are Position P/I/D Gain register
values (what the robot file's ``[gains]`` holds and users know); each goes to the backend as SI
gains (``robot.servo.gains_of``), plus the I register where the backend has one (the Dynamixel
chain; the twin's loop is PD). Each tested joint then steps by a small angle while the others
hold; then the
reference gait runs through the normal runner (ramp-in and ramp-out included). The loss is the
gait's tracking error; a candidate is rejected when a step overshoots more than allowed, never
settles, or the gait holds a joint at its torque (current) limit too long.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from snakebot.backends.base import Backend
from snakebot.config.schema import GainRegisters, RobotConfig
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, play_commands, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from snakebot.servo.dynamics import servo_dynamics
from snakebot.tuning.feasibility import SATURATION_FRACTION
from snakebot.tuning.responses import StepMetrics, chirp_commands, rms, step_commands, step_metrics
from snakebot.tuning.trace import FloatArray
from snakebot.types import PDGains

BackendSession = Callable[[], contextlib.AbstractContextManager[Backend]]


@runtime_checkable
class IntegralGain(Protocol):
    """A backend with a Position I Gain register beside the contract's PD (the Dynamixel chain)."""

    def set_position_i_gain(self, position_i: int) -> None:
        """Write the Position I Gain register of every servo."""


def apply_gains(backend: Backend, robot: RobotConfig, registers: GainRegisters) -> PDGains:
    """Set a candidate's gains on ``backend``: SI P/D through the contract, and the I register
    where the backend has one. Returns the SI gains sent."""
    gains = robot.servo.gains_of(registers)
    if isinstance(backend, IntegralGain):
        backend.set_position_i_gain(registers.position_i)
    backend.set_gains(gains)
    return gains


@dataclass(frozen=True)
class GainTest:
    """What each candidate goes through, and the limits a candidate must respect."""

    joints: tuple[int, ...]
    gait: str
    gait_params: dict[str, object] = field(default_factory=dict)
    step_rad: float = 0.2
    lead_s: float = 0.3
    step_s: float = 0.7
    gait_s: float = 6.0
    rate_hz: float = 100.0
    max_overshoot: float = 0.10
    max_saturation_s: float = 0.25


@dataclass(frozen=True)
class GainScore:
    """One candidate's results; ``loss`` is the gait tracking RMS (rad), inf when rejected.

    ``gains`` are the candidate's registers, ``pd`` the SI gains they mean for this servo.
    """

    gains: GainRegisters
    pd: PDGains
    steps: tuple[StepMetrics, ...]
    tracking_rms_rad: float
    saturation_s: float
    reason: str = ""
    step_traces: tuple[tuple[FloatArray, FloatArray, FloatArray], ...] = field(
        default=(), repr=False, compare=False
    )

    @property
    def feasible(self) -> bool:
        """True when the candidate met every limit."""
        return not self.reason

    @property
    def loss(self) -> float:
        """Gait tracking RMS in rad, or inf for a rejected candidate."""
        return self.tracking_rms_rad if self.feasible else math.inf

    def as_dict(self, joints: Sequence[int]) -> dict[str, object]:
        """JSON-ready summary with the per-joint step metrics."""
        return {
            "position_p": self.gains.position_p,
            "position_i": self.gains.position_i,
            "position_d": self.gains.position_d,
            "kp_nm_per_rad": self.pd.kp_nm_per_rad,
            "kd_nms_per_rad": self.pd.kd_nms_per_rad,
            "tracking_rms_rad": self.tracking_rms_rad,
            "saturation_s": self.saturation_s,
            "feasible": self.feasible,
            "rejected_because": self.reason or None,
            "steps": {str(j): s.as_dict() for j, s in zip(joints, self.steps, strict=True)},
        }


def evaluate_gains(
    session: BackendSession, robot: RobotConfig, gains: GainRegisters, test: GainTest
) -> GainScore:
    """Apply ``gains``, run the step tests and the reference gait, and score them."""
    with session() as backend:
        pd = apply_gains(backend, robot, gains)
        steps, traces = [], []
        for joint in test.joints:
            hold = backend.read_state().position_rad
            commands = step_commands(
                hold,
                joint,
                test.step_rad,
                robot.lower_rad,
                robot.upper_rad,
                rate_hz=test.rate_hz,
                lead_s=test.lead_s,
                step_s=test.step_s,
            )
            time_s, sent, position, _ = play(backend, robot, commands, test.rate_hz)
            t0 = time_s[0] - 1.0 / test.rate_hz
            lead = round(test.lead_s * test.rate_hz)
            steps.append(
                step_metrics(
                    time_s - t0, position[:, joint], hold[joint], commands[-1, joint], test.lead_s
                )
            )
            traces.append((time_s - t0, sent[:, joint], position[:, joint]))
            play(backend, robot, np.tile(hold, (max(lead, 1), 1)), test.rate_hz)
        tracking, saturation = _gait_tracking(backend, robot, test)
    reason = _rejection(steps, saturation, test)
    return GainScore(gains, pd, tuple(steps), tracking, saturation, reason, tuple(traces))


def measure_chirps(
    session: BackendSession,
    robot: RobotConfig,
    gains: GainRegisters,
    test: GainTest,
    amplitude_rad: float = 0.1,
    duration_s: float = 4.0,
) -> dict[int, tuple[float, tuple[FloatArray, FloatArray, FloatArray]]]:
    """Per tested joint: chirp tracking RMS (rad) and (time, command, position)."""
    out = {}
    with session() as backend:
        apply_gains(backend, robot, gains)
        for joint in test.joints:
            hold = backend.read_state().position_rad
            commands = chirp_commands(
                hold, joint, amplitude_rad, rate_hz=test.rate_hz, duration_s=duration_s
            )
            time_s, sent, position, _ = play(backend, robot, commands, test.rate_hz)
            error = sent[:, joint] - position[:, joint]
            out[joint] = (rms(error), (time_s - time_s[0], sent[:, joint], position[:, joint]))
    return out


def play(
    backend: Backend, robot: RobotConfig, commands: FloatArray, rate_hz: float
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Play commands (K, N) through the control loop behind the robot's clip-only safety
    layer (snakebot.control.runner.play_commands), one row per cycle. Returns time (K',) and
    what was sent, the positions and the efforts (K', N): K' = K on the twin, fewer where a
    slow bus made cycles late (each then plays the row of its time)."""
    records = play_commands(backend, commands, rate_hz, SafetyLayer.clip_only(robot))
    return (
        np.array([r.time_s for r in records]),
        np.array([r.command_rad for r in records]),
        np.array([r.state.position_rad for r in records]),
        np.array([r.state.effort_nm for r in records]),
    )


def candidate_grid(
    current: GainRegisters,
    maxima: GainRegisters,
    p_values: int = 4,
    d_values: int = 3,
    i_values: Sequence[int] = (),
) -> list[GainRegisters]:
    """Stage one: P log-spaced over [P/4, 4P], D over [0, 2D] (at least 0..1000), I as given,
    within the registers' ``maxima``. The current gains come first."""
    p_axis = np.geomspace(
        max(1, current.position_p // 4),
        min(maxima.position_p, 4 * max(current.position_p, 1)),
        p_values,
    )
    d_axis = np.linspace(0, min(maxima.position_d, max(2 * current.position_d, 1000)), d_values)
    out = [current]
    for i in i_values or (current.position_i,):
        for p in p_axis:
            for d in d_axis:
                gains = GainRegisters(round(float(p)), int(i), round(float(d)))
                if gains not in out:
                    out.append(gains)
    return out


def refine(
    best: GainRegisters, grid: Sequence[GainRegisters], maxima: GainRegisters
) -> list[GainRegisters]:
    """Stage two: a 3 x 3 pattern around ``best`` at half the stage-one spacing."""
    ps = sorted({g.position_p for g in grid})
    ds = sorted({g.position_d for g in grid})
    p_ratio = math.sqrt(ps[1] / ps[0]) if len(ps) > 1 and ps[0] > 0 else 1.5
    d_step = (ds[1] - ds[0]) / 2 if len(ds) > 1 else 500.0
    out = []
    for p in (
        best.position_p / math.sqrt(p_ratio),
        best.position_p,
        best.position_p * math.sqrt(p_ratio),
    ):
        for d in (best.position_d - d_step, best.position_d, best.position_d + d_step):
            gains = GainRegisters(
                int(np.clip(round(p), 1, maxima.position_p)),
                best.position_i,
                int(np.clip(round(d), 0, maxima.position_d)),
            )
            if gains not in out and gains not in grid:
                out.append(gains)
    return out


def _gait_tracking(backend: Backend, robot: RobotConfig, test: GainTest) -> tuple[float, float]:
    gait = make_gait(
        test.gait,
        robot.joint_count,
        test.gait_params,
        lower_rad=robot.lower_rad,
        upper_rad=robot.upper_rad,
    )
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    limit = SATURATION_FRACTION * servo_dynamics(robot.servo.physics, robot.gains).torque_limit_nm
    run = np.zeros(robot.joint_count)
    longest = [0.0]

    def watch(record: CycleRecord) -> None:
        # the effort the cycle measured (a read of its own would cost a bus transaction)
        nonlocal run
        saturated = np.abs(record.state.effort_nm) >= limit
        run = np.where(saturated, run + 1, 0)
        longest[0] = max(longest[0], float(run.max()) / test.rate_hz)

    plan = RunPlan(test.gait_s, test.rate_hz)
    safety = SafetyLayer.for_robot(robot)
    result = run_gait(backend, gait, safety, plan, metrics, observers=[watch])
    tracking = result.summary["tracking_rms_rad"]
    return float(tracking) if isinstance(tracking, float) else math.nan, longest[0]


def _rejection(steps: Sequence[StepMetrics], saturation_s: float, test: GainTest) -> str:
    for step in steps:
        if step.overshoot > test.max_overshoot:
            return f"overshoot {step.overshoot:.0%} > {test.max_overshoot:.0%}"
        if math.isnan(step.settling_time_s):
            return "a step never settled"
    if saturation_s > test.max_saturation_s:
        return f"held a joint at the torque limit for {saturation_s:.2f} s"
    return ""


@contextlib.contextmanager
def held(backend: Backend) -> Iterator[Backend]:
    """A session on an already connected backend (hardware): nothing to open or close."""
    yield backend
