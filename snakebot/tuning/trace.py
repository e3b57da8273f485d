"""What one evaluated run looked like, cycle by cycle, and its summary as `snakebot run` has it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from snakebot.config.schema import RobotConfig
from snakebot.control.metrics import RunMetrics
from snakebot.types import BodyState, JointState

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class Trace:
    """Samples of one run at the control rate, taken where the runner reads the state.

    Joint arrays are (K, N) in rad, rad/s or N·m for K control cycles; ``target_rad`` is what the
    gait asked for before the safety layer, ``command_rad`` what was sent. ``com_m`` is (K, 3),
    ``head_quat`` (K, 4) (w, x, y, z), ``clearance_m`` (K,) the lowest body point above the floor.
    ``stop_reason`` is "" for a run that went the full duration, else why it was cut short.
    """

    dt_s: float
    time_s: FloatArray
    target_rad: FloatArray
    command_rad: FloatArray
    position_rad: FloatArray
    velocity_rad_s: FloatArray
    effort_nm: FloatArray
    actuator_force_nm: FloatArray
    com_m: FloatArray
    head_quat: FloatArray
    clearance_m: FloatArray
    start_com_m: FloatArray
    start_head_quat: FloatArray
    stop_reason: str = ""

    @property
    def cycles(self) -> int:
        """Control cycles recorded, K."""
        return int(self.time_s.shape[0])

    @property
    def up_z(self) -> FloatArray:
        """World z of the head's up axis per cycle (K,): 1 upright, -1 upside down."""
        x, y = self.head_quat[:, 1], self.head_quat[:, 2]
        up: FloatArray = 1.0 - 2.0 * (x * x + y * y)
        return up


def summarise(trace: Trace, robot: RobotConfig, period_s: float | None) -> dict[str, object]:
    """The run summary `snakebot run --json` prints for the same run (RunMetrics on the samples).

    Feeding the samples through RunMetrics itself keeps tuned numbers identical to a replay.
    """
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    metrics.start(0.0, BodyState(trace.start_com_m, trace.start_head_quat))
    for k in range(trace.cycles):
        state = JointState(
            float(trace.time_s[k]),
            trace.position_rad[k],
            trace.velocity_rad_s[k],
            trace.effort_nm[k],
        )
        metrics.add(
            trace.command_rad[k], state, BodyState(trace.com_m[k], trace.head_quat[k]), trace.dt_s
        )
    return metrics.summary(period_s)
