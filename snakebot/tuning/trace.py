"""What one evaluated run looked like, cycle by cycle, and its summary as `snakebot run` has it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from snakebot.config.schema import RobotConfig
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.types import BodyState, JointState

FloatArray = npt.NDArray[np.float64]

SAMPLES: dict[str, str] = {
    "time_s": "",
    "target": "n",
    "command": "n",
    "position": "n",
    "velocity": "n",
    "effort": "n",
    "force": "n",
    "work": "n",
    "com": "3",
    "quat": "4",
    "clearance": "",
}
"""What a Trace samples every cycle, and each sample's trailing shape: "" a scalar, "n" one value
per joint, "3"/"4" a vector. The batch engine's arrays and ``TraceRows`` share this layout."""


@dataclass(frozen=True)
class Trace:
    """Samples of one run at the control rate, taken where the runner reads the state.

    Joint arrays are (K, N) in rad, rad/s or N·m for K control cycles; ``target_rad`` is what the
    gait asked for before the safety layer, ``command_rad`` what was sent. ``com_m`` is (K, 3),
    ``head_quat`` (K, 4) (w, x, y, z), ``clearance_m`` (K,) the lowest body point above the floor.
    ``positive_work_j`` (K, N) is each joint's positive work in each cycle, J, integrated over
    its physics steps. ``stop_reason`` is "" for a run that went the full duration, else why it
    was cut short.
    """

    dt_s: float
    time_s: FloatArray
    target_rad: FloatArray
    command_rad: FloatArray
    position_rad: FloatArray
    velocity_rad_s: FloatArray
    effort_nm: FloatArray
    actuator_force_nm: FloatArray
    positive_work_j: FloatArray
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


def make_trace(
    samples: dict[str, FloatArray],
    dt_s: float,
    start_com_m: FloatArray,
    start_head_quat: FloatArray,
    stop_reason: str,
) -> Trace:
    """A Trace from ``SAMPLES`` arrays of K cycles each ((K,) or (K, ...))."""
    a = samples
    return Trace(
        dt_s=dt_s,
        time_s=a["time_s"],
        target_rad=a["target"],
        command_rad=a["command"],
        position_rad=a["position"],
        velocity_rad_s=a["velocity"],
        effort_nm=a["effort"],
        actuator_force_nm=a["force"],
        positive_work_j=a["work"],
        com_m=a["com"],
        head_quat=a["quat"],
        clearance_m=a["clearance"],
        start_com_m=start_com_m.copy(),
        start_head_quat=start_head_quat.copy(),
        stop_reason=stop_reason,
    )


class TraceRows:
    """Trace samples taken from ``run_gait``'s cycle records, one cycle at a time.

    ``add`` takes a record with a body (a twin) and what only the twin's MjData has: the
    actuator forces (N,) and the clearance (m).
    """

    def __init__(self, joint_count: int) -> None:
        self.joint_count = joint_count
        self.rows: dict[str, list[FloatArray | float]] = {name: [] for name in SAMPLES}

    @property
    def cycles(self) -> int:
        """Cycles sampled so far."""
        return len(self.rows["time_s"])

    def add(self, record: CycleRecord, force_nm: FloatArray, clearance_m: float) -> None:
        """Sample one cycle."""
        if record.body is None:
            raise ValueError("a trace needs the body state (a simulated backend)")
        state, rows = record.state, self.rows
        rows["time_s"].append(state.time_s)
        rows["target"].append(record.target_rad.copy())
        rows["command"].append(record.command_rad.copy())
        rows["position"].append(state.position_rad)
        rows["velocity"].append(state.velocity_rad_s)
        rows["effort"].append(state.effort_nm)
        rows["force"].append(force_nm)
        if record.work_j is None:
            raise ValueError("a trace needs the work integrated per physics step (the twin)")
        rows["work"].append(record.work_j)
        rows["com"].append(record.body.com_m)
        rows["quat"].append(record.body.head_quat)
        rows["clearance"].append(clearance_m)

    def arrays(self, last: int | None = None) -> dict[str, FloatArray]:
        """The samples (of the ``last`` cycles only, when given) as (K, ...) arrays."""
        start = 0 if last is None else max(self.cycles - last, 0)
        out = {}
        for name, kind in SAMPLES.items():
            tail = () if not kind else (self.joint_count,) if kind == "n" else (int(kind),)
            values = self.rows[name][start:]
            out[name] = np.array(values, dtype=float).reshape(len(values), *tail)
        return out


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
            trace.command_rad[k],
            state,
            BodyState(trace.com_m[k], trace.head_quat[k]),
            trace.dt_s,
            trace.positive_work_j[k],
        )
    return metrics.summary(period_s)
