"""A command table as a gait: rows of a (T, N) array of joint angles, one row per control period.

Step tests, chirps and excitation records are tables made ahead of the run; played as a gait
they go through the same control loop as every other run (snakebot.control.loop), behind a
clip-only safety layer (``SafetyLayer.clip_only``: the joint limits, no slew limit, no ramp),
so what reaches the servos is exactly the table wherever it is inside the limits.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from snakebot.errors import GaitError
from snakebot.gaits.base import FloatArray, Gait, as_times, shaped


class CommandTable(Gait):
    """Row k of ``commands`` (T, N) rad from k periods of ``period_s`` into the run on.

    Time is robot time, as for any gait: a cycle that comes late (a slow bus) plays the row of
    the time it came at, so the table keeps its timing with fewer updates; before 0 the first
    row holds, after the table the last. GaitError for a table that is not (T, N) finite
    angles with T >= 1, or a period that is not a positive number.
    """

    def __init__(self, commands: npt.ArrayLike, period_s: float) -> None:
        table = np.array(commands, dtype=float)
        if table.ndim != 2 or table.shape[0] < 1 or table.shape[1] < 1:
            raise GaitError(f"command table: expected shape (T, N), got {table.shape}")
        if not np.isfinite(table).all():
            row = int(np.flatnonzero(~np.isfinite(table).all(axis=1))[0])
            raise GaitError(f"command table: row {row} holds a value that is not finite")
        if not (period_s > 0 and np.isfinite(period_s)):
            raise GaitError(f"command table: period must be positive seconds, got {period_s}")
        table.flags.writeable = False
        self.commands = table
        self.table_period_s = float(period_s)
        self.joint_count = int(table.shape[1])

    @property
    def rows(self) -> int:
        """T, the rows of the table."""
        return int(self.commands.shape[0])

    @property
    def duration_s(self) -> float:
        """How long the table plays: one period per row."""
        return self.rows * self.table_period_s

    def row_at(self, time_s: float | npt.ArrayLike) -> npt.NDArray[np.intp]:
        """The row played ``time_s`` into the run: the nearest whole period, so float sums of
        the periods (robot time on the twin) land on their row; clipped to the table."""
        t, _ = as_times("command table", time_s)
        index: npt.NDArray[np.intp] = np.clip(
            np.floor(t / self.table_period_s + 0.5), 0, self.rows - 1
        ).astype(np.intp)
        return index

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """The rows at ``time_s``: (N,) for a scalar time, (T', N) for times (T',)."""
        t, scalar = as_times("command table", time_s)
        return shaped(self.commands[self.row_at(t)], scalar)
