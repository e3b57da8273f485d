"""`log info`'s arithmetic on logs whose answers are known."""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.control.cycle import CycleRecord
from snakebot.telemetry.csv_log import TelemetryLog, column_names
from snakebot.telemetry.log_summary import summarize
from snakebot.telemetry.sink import TelemetryTee
from tests.records import record


def make_log(time_s: np.ndarray, com: np.ndarray | None, joints: int = 2) -> TelemetryLog:
    rows = len(time_s)
    command = np.tile([0.2, -0.1], (rows, 1))
    position = command - np.array([0.02, 0.01])  # constant tracking error
    velocity = np.ones((rows, joints))
    effort = np.full((rows, joints), 0.5)
    com_values = np.full((rows, 3), np.nan) if com is None else com
    values = np.column_stack(
        [time_s, np.arange(rows), command, position, velocity, effort, com_values]
    )
    return TelemetryLog(column_names(joints), values, "synthetic.csv")


def test_rate_late_cycles_tracking_and_distance() -> None:
    time_s = np.arange(101) * 0.01
    time_s[50:] += 0.02  # one period of 30 ms: late at 100 Hz
    com = np.column_stack([np.linspace(0, 0.3, 101), np.linspace(0, 0.4, 101), np.zeros(101)])
    summary = summarize(
        make_log(time_s, com),
        {"rate_hz": 100.0, "robot": {"joint_count": 2, "link": {"mass_kg": 0.1}}},
    )
    assert summary["late_cycles"] == 1
    assert summary["worst_period_s"] == pytest.approx(0.03)
    assert summary["achieved_rate_hz"] == pytest.approx(100 / 1.02)
    assert summary["tracking_rms_rad"] == pytest.approx(np.sqrt((0.02**2 + 0.01**2) / 2))
    assert summary["worst_tracking_joint"] == 0
    assert summary["distance_m"] == pytest.approx(0.5)
    assert summary["heading_deg"] == pytest.approx(np.degrees(np.arctan2(0.4, 0.3)))
    work = 2 * 0.5 * 1.0 * 1.02  # two joints at 0.5 W for 1.02 s
    assert summary["positive_work_j"] == pytest.approx(work)
    assert summary["cost_of_transport"] == pytest.approx(work / (0.3 * 9.81 * 0.5))


def test_without_a_sidecar_or_a_centre_of_mass() -> None:
    summary = summarize(make_log(np.arange(11) * 0.02, None), None)
    assert summary["rate_hz"] == pytest.approx(50.0)  # from the median period
    assert summary["late_cycles"] == 0
    assert summary["distance_m"] is None and summary["robot"] is None


class Sink:
    def __init__(self, fail_close: bool = False) -> None:
        self.rows, self.closed, self.fail_close = 0, False, fail_close

    def __call__(self, record: CycleRecord) -> None:
        self.rows += 1

    def close(self) -> None:
        self.closed = True
        if self.fail_close:
            raise OSError("disk full")


def test_a_tee_writes_to_every_sink_and_closes_them_all() -> None:
    first, second = Sink(fail_close=True), Sink()
    tee = TelemetryTee([first, second])
    tee(record(0, 0.0, np.zeros(2)))
    assert (tee.rows, first.rows, second.rows) == (1, 1, 1)
    with pytest.raises(OSError, match="disk full"):
        tee.close()
    assert first.closed and second.closed  # the second closed although the first failed
