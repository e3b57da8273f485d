"""The "simple" encoding of Serpentile Locomotion: one fixed target per joint (identity)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snakebot.errors import GaitError
from snakebot.gaits.base import FloatArray, Gait, PhasedGait, check_joint_count
from snakebot.gaits.spec import GaitSpec, ParamSpec, ParamValues


@dataclass(frozen=True)
class SimpleGait(PhasedGait):
    """Hold pose (N,) in rad at every time; an empty pose means all zeros (straight). No phase."""

    joint_count: int
    pose: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        n = check_joint_count("simple", self.joint_count)
        if self.pose and len(self.pose) != n:
            raise GaitError(
                f"simple.pose: expected {n} values in rad (one per joint), got {len(self.pose)}"
            )
        if not np.all(np.isfinite(self.pose)):
            raise GaitError("simple.pose: expected finite numbers in rad")

    @property
    def gait_label(self) -> str:
        """ "simple"."""
        return "simple"

    @property
    def phase_rates_rad_s(self) -> FloatArray:
        """Empty: a static pose."""
        return np.zeros(0)

    def _at_phases(self, phases: FloatArray) -> FloatArray:
        pose = np.asarray(self.pose or (0.0,) * self.joint_count, dtype=np.float64)
        return np.tile(pose, (phases.shape[0], 1))


def _build(joint_count: int, p: ParamValues, _lower: FloatArray, _upper: FloatArray) -> Gait:
    return SimpleGait(joint_count, p.numbers("pose"))


SPEC = GaitSpec(
    name="simple",
    summary="Identity encoding: hold one target per joint (Serpentile Locomotion's 'simple').",
    params=(ParamSpec("pose", "rad", (), "N joint targets head to tail; empty = all zeros"),),
    factory=_build,
)
