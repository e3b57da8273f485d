"""A standing wave: every joint swings in phase, its amplitude shaped along the body.

theta_i(t) = amplitude * cos(spatial_freq * i) * sin(omega * t), in rad, joints i = 0..N-1 head
to tail. Unlike a travelling wave (serpenoid) the shape does not move along the body, so the
snake rocks in place rather than crawls: a simple gait with a clear signature in a log.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from snakebot.gaits import Gait, GaitSpec, ParamSpec, ParamValues
from snakebot.gaits.base import FloatArray, as_times, check_finite, check_joint_count, shaped


@dataclass(frozen=True)
class StandingWaveGait(Gait):
    """amplitude (rad) * cos(spatial_freq (rad/joint) * i) * sin(omega (rad/s) * t)."""

    joint_count: int
    amplitude: float = 0.5
    omega: float = math.pi
    spatial_freq: float = math.pi / 4

    def __post_init__(self) -> None:
        check_joint_count("standing_wave", self.joint_count)
        check_finite(
            "standing_wave",
            amplitude=self.amplitude,
            omega=self.omega,
            spatial_freq=self.spatial_freq,
        )

    @property
    def period_s(self) -> float | None:
        """2*pi/|omega| in s; None when omega is 0."""
        return None if self.omega == 0.0 else 2.0 * math.pi / abs(self.omega)

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """Joint angles in rad: (N,) for a scalar time in s, (T, N) for times (T,)."""
        t, scalar = as_times("standing_wave", time_s)
        shape = self.amplitude * np.cos(self.spatial_freq * np.arange(self.joint_count))
        return shaped(np.sin(self.omega * t)[:, None] * shape[None, :], scalar)


def _build(joint_count: int, p: ParamValues, _lower: FloatArray, _upper: FloatArray) -> Gait:
    return StandingWaveGait(
        joint_count,
        amplitude=p.number("amplitude"),
        omega=p.number("omega"),
        spatial_freq=p.number("spatial_freq"),
    )


SPEC = GaitSpec(
    name="standing_wave",
    summary="Standing wave: all joints swing in phase, amplitude*cos(spatial_freq*i) on the body.",
    params=(
        ParamSpec(
            "amplitude",
            "rad",
            0.5,
            "peak joint angle (at the head)",
            bounds=(0.1, 1.0),
            tunable=True,
        ),
        ParamSpec(
            "omega", "rad/s", math.pi, "swing frequency", bounds=(0.5, 4 * math.pi), tunable=True
        ),
        ParamSpec(
            "spatial_freq", "rad/joint", math.pi / 4, "shape along the body", bounds=(0.0, math.pi)
        ),
    ),
    factory=_build,
)
