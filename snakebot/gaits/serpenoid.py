"""Hirose's discrete serpenoid: one travelling sine wave over all joints (planar snakes)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from snakebot.gaits.base import FloatArray, Gait, PhasedGait, check_finite, check_joint_count
from snakebot.gaits.spec import GaitSpec, JointAxes, LiveRoles, ParamSpec, ParamValues


@dataclass(frozen=True)
class SerpenoidGait(PhasedGait):
    """theta_i(t) = amplitude*sin(omega*t - i*phase_lag) + offset, in rad, for joints i = 0..N-1.

    A positive phase_lag makes joint i lag joint i-1, so the wave travels head -> tail. One
    phase, phi = omega*t: ``targets_at_phase([phi])``.
    """

    joint_count: int
    amplitude: float = 0.4
    omega: float = math.pi
    phase_lag: float = 0.7
    offset: float = 0.0
    _rates: FloatArray = field(init=False, repr=False, compare=False)
    _lags: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        check_joint_count("serpenoid", self.joint_count)
        check_finite(
            "serpenoid",
            amplitude=self.amplitude,
            omega=self.omega,
            phase_lag=self.phase_lag,
            offset=self.offset,
        )
        object.__setattr__(self, "_rates", np.array([self.omega]))
        object.__setattr__(self, "_lags", self.phase_lag * np.arange(self.joint_count, dtype=float))

    @property
    def gait_label(self) -> str:
        """ "serpenoid"."""
        return "serpenoid"

    @property
    def phase_rates_rad_s(self) -> FloatArray:
        """[omega] in rad/s."""
        return self._rates

    @property
    def period_s(self) -> float | None:
        """2*pi/|omega| in s; None when omega is 0 (a frozen curve)."""
        return None if self.omega == 0.0 else 2.0 * math.pi / abs(self.omega)

    def _at_phases(self, phases: FloatArray) -> FloatArray:
        wave: FloatArray = self.amplitude * np.sin(phases[:, :1] - self._lags[None, :])
        return wave + self.offset

    def _at_time(self, time_s: float) -> FloatArray:
        # _at_phases's floats at phase 0 + omega * t, in four numpy calls (the control loop's).
        wave: FloatArray = self.amplitude * np.sin((0.0 + time_s * self.omega) - self._lags)
        return wave + self.offset


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
    live=LiveRoles(
        amplitude=("amplitude",),
        frequency=("omega",),
        spatial_frequency=("phase_lag",),
        offset=("offset",),
    ),
    axes=JointAxes("yaw", "yaw", False, "it is a planar wave (lateral undulation)"),
)
