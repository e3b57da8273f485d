"""Mass-spring bodies (Miller 1988) as frozen dataclasses; SI units inside.

Miller's table gives spring constants without units. A body file states them in his units and the
scale that turns them into SI: with the point mass m as the mass unit and ``time_unit_s`` T as the
time unit, k_SI = k m / T^2 (N/m) and D_SI = D m / T (N·s/m). The damping ratio of one spring on
one point, D / (2 sqrt(k)), has no units and so stays the paper's whatever m and T are.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from snakebot.types import StopPolicy

ChannelAxis = Literal["yaw", "pitch", "axial"]
CHANNEL_AXES: tuple[ChannelAxis, ...] = ("yaw", "pitch", "axial")

# Miller (1988), "Sample Parameter Values": spring strength k and damping D per animal.
MILLER_TABLE: dict[str, tuple[float, float]] = {
    "worm": (1.5, 0.9),
    "snake": (0.5, 3.5),
    "caterpillar": (0.3, 0.6),
}


@dataclass(frozen=True)
class LatticeConfig:
    """The body's cubes: how many, their sides in m, and each corner's point mass."""

    segments: int
    segment_length_m: float
    width_m: float
    height_m: float
    point_mass_kg: float
    point_radius_m: float


@dataclass(frozen=True)
class SpringConfig:
    """Spring strength ``k`` and damping ``damping`` in Miller's units, and the time unit.

    ``preset`` names the row of Miller's table they came from ("" when given by hand).
    """

    k: float
    damping: float
    time_unit_s: float
    preset: str = ""

    @property
    def damping_ratio(self) -> float:
        """D / (2 sqrt(k)): the paper's dimensionless damping of one spring on one point."""
        return self.damping / (2.0 * math.sqrt(self.k))


@dataclass(frozen=True)
class MuscleConfig:
    """What the controller drives: channels per segment, their limits and how fast they move.

    ``max_bend_rad`` bounds yaw and pitch, ``max_contraction`` the axial strain (both signs);
    ``max_rate_per_s`` is the safety layer's slew limit (rad/s for bends, 1/s for strain).
    """

    channels: tuple[ChannelAxis, ...]
    max_bend_rad: float
    max_contraction: float
    max_rate_per_s: float
    volume_preservation: bool


@dataclass(frozen=True)
class GroundConfig:
    """Floor friction coefficient (isotropic Coulomb) and Miller's directional rule on or off."""

    friction: float
    directional: bool


@dataclass(frozen=True)
class BodySafety:
    """The safety layer's ramp and what ``close`` leaves: muscles holding or relaxed."""

    ramp_s: float
    stop_policy: StopPolicy


@dataclass(frozen=True)
class ChannelConfig:
    """One controller channel, the soft body's "joint": its segment, axis and limits.

    Limits are rad for yaw and pitch and strain (dimensionless) for axial.
    """

    segment: int
    axis: ChannelAxis
    lower_rad: float
    upper_rad: float


@dataclass(frozen=True)
class BodyConfig:
    """A whole mass-spring body; quacks like a RobotConfig where the control stack needs it
    (joints, limits, speed, safety, length and mass)."""

    name: str
    source: Path
    lattice: LatticeConfig
    springs: SpringConfig
    muscles: MuscleConfig
    ground: GroundConfig
    safety: BodySafety
    timestep_s: float

    @property
    def joints(self) -> tuple[ChannelConfig, ...]:
        """Channels segment by segment, ``muscles.channels`` within each segment."""
        out = []
        for segment in range(self.lattice.segments):
            for axis in self.muscles.channels:
                limit = (
                    self.muscles.max_contraction if axis == "axial" else self.muscles.max_bend_rad
                )
                out.append(ChannelConfig(segment, axis, -limit, limit))
        return tuple(out)

    @property
    def joint_count(self) -> int:
        """N = segments * channels per segment."""
        return self.lattice.segments * len(self.muscles.channels)

    @property
    def lower_rad(self) -> np.ndarray:
        """Lower channel limits (N,)."""
        return np.array([j.lower_rad for j in self.joints])

    @property
    def upper_rad(self) -> np.ndarray:
        """Upper channel limits (N,)."""
        return np.array([j.upper_rad for j in self.joints])

    @property
    def max_speed_rad_s(self) -> float:
        """The safety layer's slew limit for every channel."""
        return self.muscles.max_rate_per_s

    @property
    def body_length_m(self) -> float:
        """Head ring to tail ring, relaxed."""
        return self.lattice.segments * self.lattice.segment_length_m

    @property
    def point_count(self) -> int:
        """Point masses: four per ring, one ring more than segments."""
        return 4 * (self.lattice.segments + 1)

    @property
    def total_mass_kg(self) -> float:
        """Mass of all points."""
        return self.point_count * self.lattice.point_mass_kg

    @property
    def stiffness_n_per_m(self) -> float:
        """k in SI: k * m / T^2."""
        return self.springs.k * self.lattice.point_mass_kg / self.springs.time_unit_s**2

    @property
    def damping_ns_per_m(self) -> float:
        """D in SI: D * m / T."""
        return self.springs.damping * self.lattice.point_mass_kg / self.springs.time_unit_s
