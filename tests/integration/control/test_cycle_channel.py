"""A new channel is one field: the record carries it from the backend to the sinks that show it.

A twin that also measures motor current (one more field of the state it reads) runs through
``run_gait`` untouched: the loop hands the record on as it is, a sink that shows current gets
every cycle's, and the CSV log beside it writes the same columns as ever.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.control.cycle import CycleRecord, CycleSink
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from snakebot.telemetry import CsvTelemetryWriter, column_names, read_log
from snakebot.telemetry.sink import TelemetryTee
from snakebot.types import JointState

AMPS_PER_NM = 0.8


@dataclass(frozen=True)
class StateWithCurrent(JointState):
    """The joint state plus the new channel: motor current per joint (N,) A."""

    current_a: np.ndarray


class CurrentTwin(TwinBackend):
    """The twin, reading one more channel (a current sensor: current from torque)."""

    def _read_state(self) -> JointState:
        state = super()._read_state()
        return StateWithCurrent(**vars(state), current_a=np.abs(state.effort_nm) * AMPS_PER_NM)


class CurrentSink:
    """A sink that chooses to show the new channel."""

    def __init__(self) -> None:
        self.rows = 0
        self.current: list[np.ndarray] = []
        self.effort: list[np.ndarray] = []

    def __call__(self, record: CycleRecord) -> None:
        state = record.state
        assert isinstance(state, StateWithCurrent)
        self.current.append(state.current_a)
        self.effort.append(state.effort_nm)
        self.rows += 1

    def close(self) -> None:
        pass


def test_a_new_channel_reaches_the_sink_that_shows_it_and_no_other_changes(
    tmp_path: Path,
) -> None:
    robot = load_robot("snake8")
    current = CurrentSink()
    assert isinstance(current, CycleSink)
    path = tmp_path / "run.csv"
    with CurrentTwin(robot) as twin, CsvTelemetryWriter(path, robot.joint_count) as csv:
        result = run_gait(
            twin,
            make_gait("serpenoid", robot.joint_count),
            SafetyLayer.for_robot(robot),
            RunPlan(duration_s=0.5),
            RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
            log=TelemetryTee([csv, current]),
        )
    log = read_log(path)
    assert current.rows == csv.rows == result.log_rows == len(log.values) > 50
    np.testing.assert_array_equal(
        np.array(current.current), np.abs(np.array(current.effort)) * AMPS_PER_NM
    )
    assert np.abs(np.array(current.current)).max() > 0  # the servos worked: a real signal
    assert log.columns == column_names(robot.joint_count)  # the CSV did not change
    np.testing.assert_allclose(
        log.joints("effort_nm"), np.array(current.effort), rtol=1e-5, atol=1e-9
    )
