"""Joint commands for a batch of B runs, cycle by cycle: gaits through the safety layer, or arrays.

Both give (targets, commands), each (B, N) in rad: what was asked for and what is sent.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

import numpy as np

from snakebot.config.schema import RobotConfig
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import Gait
from snakebot.tuning.trace import FloatArray


class BatchCommands(Protocol):
    """A source of joint commands for B runs stepped together at a fixed control period."""

    @property
    def size(self) -> int:
        """B, the number of runs."""

    @property
    def length(self) -> float:
        """Cycles available: the array length, or inf for gaits."""

    @property
    def open_loop(self) -> bool:
        """True when the commands ignore the measured poses, so cycles can be batched."""

    def reset(self, measured_rad: FloatArray) -> None:
        """Start from the measured poses (B, N)."""

    def __call__(
        self, cycle: int, time_s: float, measured_rad: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """(targets, commands), each (B, N) rad, for control cycle ``cycle`` at gait time
        ``time_s`` (robot time since the start), given the measured poses (B, N)."""


def is_open_loop(gait: Gait) -> bool:
    """True when ``gait.command`` ignores the measured pose (as the gait declares)."""
    return not gait.uses_measured_pose


class GaitCommands:
    """B gaits through one SafetyLayer tiled over (B*N,), exactly as ``run_gait`` sends them.

    The safety layer works elementwise, so one layer over the flattened batch gives each run the
    same clipping, slew limit and ramp-in as its own layer would. Targets come from
    ``gait.command`` one cycle at a time, as in the runner: numpy's vectorised sin can differ
    from the one-element path in the last bit, and a replay must match to the bit.
    """

    def __init__(self, gaits: Sequence[Gait], robot: RobotConfig, dt_s: float) -> None:
        self.gaits = list(gaits)
        self.dt_s = dt_s
        count = len(self.gaits)
        self.safety = SafetyLayer(
            np.tile(robot.lower_rad, count),
            np.tile(robot.upper_rad, count),
            robot.max_speed_rad_s,
            robot.safety.ramp_s,
        )

    @property
    def size(self) -> int:
        """B, the number of gaits."""
        return len(self.gaits)

    @property
    def length(self) -> float:
        """Gaits never run out of commands."""
        return math.inf

    @property
    def open_loop(self) -> bool:
        """True unless a gait uses the measured pose (keyframes with error advance, say)."""
        return all(is_open_loop(gait) for gait in self.gaits)

    def reset(self, measured_rad: FloatArray) -> None:
        """Reset every gait and start the safety layer from the measured poses (B, N)."""
        for gait in self.gaits:
            gait.reset()
        self.safety.reset(measured_rad.ravel())

    def __call__(
        self, cycle: int, time_s: float, measured_rad: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Gait targets at ``time_s`` and the safety layer's commands, each (B, N)."""
        targets = np.stack(
            [
                gait.command(time_s, measured)
                for gait, measured in zip(self.gaits, measured_rad, strict=True)
            ]
        )
        commands = self.safety.filter(targets.ravel(), self.dt_s, self.safety.ramp_in(time_s))
        return targets, commands.reshape(targets.shape)


class ArrayCommands:
    """Precomputed commands (B, K, N) rad, sent as they are (log replay, step and chirp tests)."""

    def __init__(self, commands: FloatArray) -> None:
        if commands.ndim != 3:
            raise ValueError(f"commands must have shape (B, K, N), got {commands.shape}")
        self.commands = commands

    @property
    def size(self) -> int:
        """B, the number of runs."""
        return int(self.commands.shape[0])

    @property
    def length(self) -> float:
        """K, the number of cycles stored."""
        return float(self.commands.shape[1])

    @property
    def open_loop(self) -> bool:
        """Always: the commands are fixed."""
        return True

    def reset(self, measured_rad: FloatArray) -> None:
        """Nothing to reset: the commands are fixed."""

    def __call__(
        self, cycle: int, time_s: float, measured_rad: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The stored commands of ``cycle`` as both targets and commands."""
        row = self.commands[:, cycle]
        return row, row
