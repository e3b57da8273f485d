"""Summary metrics of a run, accumulated per cycle in O(1) memory: an observer of the records.

Positive work is what the backend integrated over every physics step where it did (the twin,
the batched engine, a soft body: ``CycleRecord.work_j``), so work and cost of transport do not
depend on the control rate; on a backend that only samples it is effort times velocity at the
end of each cycle times the period.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from snakebot.types import BodyState, JointState, positive_power_w

if TYPE_CHECKING:
    from snakebot.control.cycle import CycleRecord

GRAVITY_M_S2 = 9.81


@dataclass
class RunMetrics:
    """Accumulates tracking error, commands, positive joint work and the COM path."""

    joint_count: int
    body_length_m: float
    mass_kg: float
    cycles: int = 0
    start_time_s: float | None = None
    end_time_s: float = 0.0
    start_com: np.ndarray | None = None
    end_com: np.ndarray | None = None
    _squared_error_sum: float = 0.0
    _max_abs_command: float = 0.0
    _positive_work_j: float = 0.0
    _turn_rad: float = 0.0
    _last_yaw: float | None = None
    control_period_s: float | None = None
    extra: dict[str, object] = field(default_factory=dict)

    def start(
        self, time_s: float, body: BodyState | None, control_period_s: float | None = None
    ) -> None:
        """Mark the beginning of the scored window; ``control_period_s`` is the period each
        record observed (``__call__``) accounts for (None: the time the cycle took)."""
        self.control_period_s = control_period_s
        self.start_time_s = time_s
        self.start_com = None if body is None else body.com_m.copy()
        self.end_com = self.start_com
        self._last_yaw = None if body is None else head_yaw_rad(body.head_quat)

    def __call__(self, record: CycleRecord) -> None:
        """Observe a cycle's record: a scored cycle counts (the ramp-out's do not)."""
        if record.scored:
            period = self.control_period_s
            dt_s = record.period_s if period is None else period
            self.add(record.command_rad, record.state, record.body, dt_s, record.work_j)

    def add(
        self,
        command: np.ndarray,
        state: JointState,
        body: BodyState | None,
        dt_s: float,
        work_j: np.ndarray | None = None,
    ) -> None:
        """Account one control cycle of ``dt_s`` s; ``work_j`` (N,) J is each joint's positive
        work in it integrated by the backend (None: sampled from ``state``)."""
        error = command - state.position_rad
        self._squared_error_sum += float(error @ error)
        self._max_abs_command = max(self._max_abs_command, *map(abs, command.tolist()))
        if work_j is None:
            power = positive_power_w(state.effort_nm, state.velocity_rad_s)
            self._positive_work_j += float(power.sum()) * dt_s
        else:
            self._positive_work_j += float(work_j.sum())
        self.cycles += 1
        self.end_time_s = state.time_s
        if body is not None:
            self.end_com = body.com_m
            yaw = head_yaw_rad(body.head_quat)
            if self._last_yaw is not None:
                self._turn_rad += math.remainder(yaw - self._last_yaw, 2 * math.pi)
            self._last_yaw = yaw

    @property
    def positive_work_j(self) -> float:
        """Positive joint work of the scored cycles so far, J."""
        return self._positive_work_j

    def summary(self, period_s: float | None) -> dict[str, object]:
        """The run's summary, JSON-ready; distance-based keys are None without a COM."""
        start = self.start_time_s if self.start_time_s is not None else 0.0
        duration = max(self.end_time_s - start, 0.0)
        gait_cycles = round(duration / period_s, 6) if period_s else None
        tracking = math.sqrt(self._squared_error_sum / max(self.cycles * self.joint_count, 1))
        out: dict[str, object] = {
            "duration_s": round(duration, 6),
            "joints": self.joint_count,
            "body_length_m": self.body_length_m,
            "control_cycles": self.cycles,
            "cycles": gait_cycles,
            "tracking_rms_rad": tracking,
            "max_abs_command_rad": self._max_abs_command,
            "positive_work_j": self._positive_work_j,
        }
        if self.start_com is None or self.end_com is None:
            out.update(
                distance_m=None,
                displacement_m=None,
                speed_mps=None,
                heading_deg=None,
                body_lengths_per_cycle=None,
                cost_of_transport=None,
                turn_deg=None,
            )
            return out
        dx, dy = (self.end_com[:2] - self.start_com[:2]).tolist()
        distance = math.hypot(dx, dy)
        out.update(
            distance_m=distance,
            displacement_m=[dx, dy],
            speed_mps=distance / duration if duration > 0 else 0.0,
            turn_deg=math.degrees(self._turn_rad),
            heading_deg=math.degrees(math.atan2(dy, dx)) if distance > 0 else 0.0,
            body_lengths_per_cycle=(distance / self.body_length_m / gait_cycles)
            if gait_cycles
            else None,
            cost_of_transport=(self._positive_work_j / (self.mass_kg * GRAVITY_M_S2 * distance))
            if distance > 1e-9
            else None,
        )
        return out


def cycle_work_j(before: JointState, after: JointState) -> np.ndarray | None:
    """Each joint's positive work (N,) J between two states of a backend that integrates it
    (``JointState.positive_work_j``); None where either state has none."""
    if before.positive_work_j is None or after.positive_work_j is None:
        return None
    work: np.ndarray = after.positive_work_j - before.positive_work_j
    return work


def head_yaw_rad(quat: np.ndarray) -> float:
    """Heading of the head module's forward (+x) axis in the world's horizontal plane."""
    w, x, y, z = quat.tolist()
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
