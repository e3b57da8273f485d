"""Hirose's discrete serpenoid: one travelling sine wave over all joints (planar snakes)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from snakebot.gaits.base import FloatArray, Gait, as_times, check_finite, check_joint_count, shaped
from snakebot.gaits.spec import GaitSpec, ParamSpec, ParamValues


@dataclass(frozen=True)
class SerpenoidGait(Gait):
    """theta_i(t) = amplitude*sin(omega*t - i*phase_lag) + offset, in rad, for joints i = 0..N-1.

    A positive phase_lag makes joint i lag joint i-1, so the wave travels head -> tail.
    """

    joint_count: int
    amplitude: float = 0.4
    omega: float = math.pi
    phase_lag: float = 0.7
    offset: float = 0.0

    def __post_init__(self) -> None:
        check_joint_count("serpenoid", self.joint_count)
        check_finite(
            "serpenoid",
            amplitude=self.amplitude,
            omega=self.omega,
            phase_lag=self.phase_lag,
            offset=self.offset,
        )

    @property
    def period_s(self) -> float | None:
        """2*pi/|omega| in s; None when omega is 0 (a frozen curve)."""
        return None if self.omega == 0.0 else 2.0 * math.pi / abs(self.omega)

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """Joint angles in rad: (N,) for a scalar time in s, (T, N) for times (T,)."""
        t, scalar = as_times("serpenoid", time_s)
        joints = np.arange(self.joint_count, dtype=np.float64)
        phase = self.omega * t[:, None] - self.phase_lag * joints[None, :]
        return shaped(self.amplitude * np.sin(phase) + self.offset, scalar)


def _build(joint_count: int, p: ParamValues, _lower: FloatArray, _upper: FloatArray) -> Gait:
    return SerpenoidGait(
        joint_count,
        amplitude=p.number("amplitude"),
        omega=p.number("omega"),
        phase_lag=p.number("phase_lag"),
        offset=p.number("offset"),
    )


# Tuning bounds: frequencies reach 3 Hz, past what the servos can play at useful amplitudes: the
# envelope (the servo's speed), not the box, should decide how fast a gait can go.
SPEC = GaitSpec(
    name="serpenoid",
    summary=(
        "Hirose serpenoid on every joint: amplitude*sin(omega*t - i*phase_lag) + offset; "
        "for planar (all-yaw) snakes; use lateral_undulation on yaw/pitch snakes."
    ),
    params=(
        ParamSpec(
            "amplitude",
            "rad",
            0.4,
            "joint amplitude (0.4-0.6 rad on real robots)",
            bounds=(0.05, 1.2),
        ),
        ParamSpec(
            "omega",
            "rad/s",
            math.pi,
            "temporal frequency (pi rad/s = 0.5 Hz)",
            bounds=(0.5, 6 * math.pi),
            tunable=True,
        ),
        ParamSpec(
            "phase_lag",
            "rad",
            0.7,
            "phase lag per joint; > 0 sends the wave head -> tail",
            bounds=(0.1, math.pi / 2),
            tunable=True,
        ),
        ParamSpec(
            "offset",
            "rad",
            0.0,
            "constant bias on every joint; nonzero turns",
            bounds=(-0.3, 0.3),
        ),
    ),
    factory=_build,
)
