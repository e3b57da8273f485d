"""The "simple" encoding of Serpentile Locomotion: one fixed target per joint (identity)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from snakebot.errors import GaitError
from snakebot.gaits.base import FloatArray, Gait, as_times, check_joint_count, shaped
from snakebot.gaits.spec import GaitSpec, ParamSpec, ParamValues


@dataclass(frozen=True)
class SimpleGait(Gait):
    """Hold pose (N,) in rad at every time; an empty pose means all zeros (straight)."""

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

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """The pose (N,) in rad for a scalar time, repeated (T, N) for times (T,)."""
        t, scalar = as_times("simple", time_s)
        pose = np.asarray(self.pose or (0.0,) * self.joint_count, dtype=np.float64)
        return shaped(np.tile(pose, (t.size, 1)), scalar)


def _build(joint_count: int, p: ParamValues, _lower: FloatArray, _upper: FloatArray) -> Gait:
    return SimpleGait(joint_count, p.numbers("pose"))


SPEC = GaitSpec(
    name="simple",
    summary="Identity encoding: hold one target per joint (Serpentile Locomotion's 'simple').",
    params=(ParamSpec("pose", "rad", (), "N joint targets head to tail; empty = all zeros"),),
    factory=_build,
)
