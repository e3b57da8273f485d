"""Value types shared by config, control and the backends: SI units and radians throughout.

Only numpy is imported here, so ``config/`` and ``control/`` can use these without importing
``backends/`` (nothing imports upward). Servo ticks and register units never appear in them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

StopPolicy = Literal["hold", "limp"]
"""What the servos do after a run's ramp-out: hold the last pose or go limp (torque off)."""


@dataclass(frozen=True)
class JointState:
    """One snapshot of every joint, head to tail.

    ``position_rad``, ``velocity_rad_s`` and ``effort_nm`` have shape (N,); ``time_s`` is robot
    time (simulated on the twin, monotonic wall clock on hardware). ``positive_work_j`` (N,) is
    the positive work each joint has put in since the backend connected or reset, J, integrated
    over every physics step by a simulated backend (so it does not depend on the control rate);
    None where the backend only samples (a servo bus: the run's metrics then integrate effort
    times velocity at the control rate).
    """

    time_s: float
    position_rad: np.ndarray
    velocity_rad_s: np.ndarray
    effort_nm: np.ndarray
    positive_work_j: np.ndarray | None = field(default=None, kw_only=True)


def positive_power_w(effort_nm: np.ndarray, velocity_rad_s: np.ndarray) -> np.ndarray:
    """The mechanical power each joint puts in, W: effort times velocity where positive, 0 where
    the joint is being driven (negative power) or a value is missing (NaN). Any shape (..., N);
    positive work is its integral: over every physics step on a simulated backend
    (``JointState.positive_work_j``), else its sum times the control period."""
    power = effort_nm * velocity_rad_s
    return np.where(power > 0.0, power, 0.0)


@dataclass(frozen=True)
class BodyState:
    """Whole-body quantities only a twin (or a motion-capture rig) can measure.

    ``com_m`` is the centre of mass (3,) in the world frame, ``head_quat`` the head link's
    orientation (w, x, y, z). ``head_gyro_rad_s`` (3,) is what a gyro in the head reads: its
    angular velocity in its own frame (None where no IMU is modelled).
    """

    com_m: np.ndarray
    head_quat: np.ndarray
    head_gyro_rad_s: np.ndarray | None = None


@dataclass(frozen=True)
class JointCommand:
    """Goal positions for every joint, head to tail, shape (N,), radians."""

    position_rad: np.ndarray


@dataclass(frozen=True)
class PDGains:
    """Position-loop gains in SI, the same for every joint: what crosses the Backend contract.

    ``kp_nm_per_rad`` is the stiffness (N·m per rad of position error), ``kd_nms_per_rad`` the
    damping (N·m per rad/s of joint speed). The twin uses them as they are; the Dynamixel backend
    turns them into its Position P/D Gain registers (snakebot.servo.GainMapping). Both must be
    finite and >= 0 (ValueError otherwise).
    """

    kp_nm_per_rad: float
    kd_nms_per_rad: float = 0.0

    def __post_init__(self) -> None:
        for name in ("kp_nm_per_rad", "kd_nms_per_rad"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and 0.0 <= value < float("inf")):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")


@dataclass
class CycleStats:
    """Timing bookkeeping a real-time backend keeps for the runner's summary."""

    overruns: int = 0
    worst_lateness_s: float = 0.0
    extra: dict[str, float] = field(default_factory=dict)
