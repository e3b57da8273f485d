"""A command table played as a gait: row k from k periods on, as robot time sums them."""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.control.cycle import CycleSchedule
from snakebot.errors import GaitError
from snakebot.gaits.table import CommandTable


def test_each_cycle_of_the_schedule_plays_its_own_row_once() -> None:
    table = np.arange(30.0).reshape(10, 3)
    gait = CommandTable(table, 0.01)
    # the twin's gait times: 0.01 s summed 0.002 s step by step, as MuJoCo sums data.time
    times = CycleSchedule(100.0, gait.duration_s, timestep_s=0.002).cycle_times()[:-1]
    assert len(times) == 10
    played = np.array([gait.command(t, np.zeros(3)) for t in times])
    np.testing.assert_array_equal(played, table)
    assert not gait.uses_measured_pose  # open loop: the batched engine could play it too


def test_a_late_cycle_plays_the_row_of_its_time_and_the_ends_hold() -> None:
    table = np.arange(20.0).reshape(10, 2)
    gait = CommandTable(table, 0.01)
    np.testing.assert_array_equal(gait.targets(0.0449), table[4])  # 4.49 periods: row 4
    np.testing.assert_array_equal(gait.targets(0.0451), table[5])
    np.testing.assert_array_equal(gait.targets(5.0), table[-1])
    np.testing.assert_array_equal(gait.targets(np.array([0.0, 0.02])), table[[0, 2]])


@pytest.mark.parametrize(
    ("table", "period", "message"),
    [
        (np.zeros(4), 0.01, r"shape \(T, N\)"),
        (np.zeros((0, 3)), 0.01, r"shape \(T, N\)"),
        (np.array([[0.0, 1.0], [np.nan, 0.0]]), 0.01, "row 1"),
        (np.zeros((2, 2)), 0.0, "period"),
    ],
)
def test_a_table_that_cannot_be_played_is_refused(
    table: np.ndarray, period: float, message: str
) -> None:
    with pytest.raises(GaitError, match=message):
        CommandTable(table, period)
