"""Joint commands for a batch of B runs, cycle by cycle: gaits through the safety layer, or arrays.

Both give (targets, commands), each (B, N) in rad: what was asked for and what is sent.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

from snakebot.config.schema import RobotConfig
from snakebot.control.cycle import CycleSchedule, GaitCycle
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import Gait
from snakebot.tuning.trace import FloatArray


class BatchCommands(Protocol):
    """A source of joint commands for B runs stepped together on one cycle schedule."""

    @property
    def size(self) -> int:
        """B, the number of runs."""

    @property
    def length(self) -> float:
        """Cycles available: the array length, or inf for gaits."""

    @property
    def open_loop(self) -> bool:
        """True when the commands ignore the measured poses, so cycles can be batched."""

    def reset(self, measured_rad: FloatArray, schedule: CycleSchedule) -> None:
        """Start from the measured poses (B, N) on ``schedule``."""

    def __call__(
        self, cycle: int, time_s: float, measured_rad: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """(targets, commands), each (B, N) rad, for control cycle ``cycle`` at gait time
        ``time_s`` (robot time since the start), given the measured poses (B, N)."""


class GaitCommands:
    """B gaits through the runner's ``GaitCycle`` (one safety layer tiled over (B*N,)), on the
    runner's schedule: exactly what ``run_gait`` sends, run by run."""

    def __init__(self, gaits: Sequence[Gait], robot: RobotConfig) -> None:
        self.cycle = GaitCycle.tiled(gaits, SafetyLayer.for_robot(robot))
        self.schedule: CycleSchedule | None = None
        self._last_time_s: float | None = None

    @property
    def gaits(self) -> list[Gait]:
        """The B gaits."""
        return self.cycle.gaits

    @property
    def size(self) -> int:
        """B, the number of gaits."""
        return self.cycle.size

    @property
    def length(self) -> float:
        """Gaits never run out of commands."""
        return math.inf

    @property
    def open_loop(self) -> bool:
        """True unless a gait uses the measured pose (keyframes with error advance, say)."""
        return self.cycle.open_loop

    def reset(self, measured_rad: FloatArray, schedule: CycleSchedule) -> None:
        """Reset every gait and start the safety layer from the measured poses (B, N)."""
        self.cycle.reset(measured_rad)
        self.schedule = schedule
        self._last_time_s = None

    def __call__(
        self, cycle: int, time_s: float, measured_rad: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Gait targets at ``time_s`` and the safety layer's commands, each (B, N)."""
        targets = self.cycle.targets(time_s, measured_rad)
        return targets, self.send(cycle, time_s, targets)

    def send(self, cycle: int, time_s: float, targets_rad: FloatArray) -> FloatArray:
        """What the safety layer sends (B, N) for the gaits' ``targets_rad`` (B, N) of control
        cycle ``cycle`` at gait time ``time_s``: the commands half of ``__call__``, for a caller
        that computed the targets of many cycles at once (Gait.targets over an array of times)."""
        schedule = self.schedule
        if schedule is None:
            raise RuntimeError("GaitCommands used before reset()")
        last, self._last_time_s = self._last_time_s, time_s
        slew_s = schedule.slew_period_s(cycle, None if last is None else time_s - last)
        return self.cycle.commands(targets_rad, slew_s, schedule.ramp_in(time_s))


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

    def reset(self, measured_rad: FloatArray, schedule: CycleSchedule) -> None:
        """Nothing to reset: the commands are fixed."""

    def __call__(
        self, cycle: int, time_s: float, measured_rad: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The stored commands of ``cycle`` as both targets and commands."""
        row = self.commands[:, cycle]
        return row, row
