"""The one cycle schedule every control loop follows: cycle times, scored window, ramps, slew."""

from __future__ import annotations

import itertools
import math

import pytest

from snakebot.control.cycle import MAX_SLEW_PERIODS, CycleSchedule


def test_the_planned_cycles_are_the_whole_periods_that_fit_the_duration() -> None:
    schedule = CycleSchedule(100.0, 1.5, timestep_s=0.002)
    times = schedule.cycle_times()
    assert schedule.substeps == 5
    assert schedule.planned_cycles == len(times) - 1 == 150
    assert times[0] == 0.0 and times[-1] == pytest.approx(1.5)
    # Summed step by step as MuJoCo sums data.time, not k * period.
    now = 0.0
    for _ in range(5 * 37):
        now += 0.002
    assert times[37] == now
    assert all(schedule.in_gait(t) for t in times[:-1]) and not schedule.in_gait(times[-1])
    assert schedule.cycle_times(10) == times[:11]


def test_an_open_ended_schedule_never_ends_the_gait_itself() -> None:
    schedule = CycleSchedule(50.0)
    assert schedule.in_gait(1e9)
    with pytest.raises(ValueError, match="open-ended"):
        schedule.planned_cycles  # noqa: B018
    assert len(CycleSchedule(50.0, timestep_s=0.002).cycle_times(4)) == 5


def test_the_ramps_start_and_end_at_rest_smoothly() -> None:
    schedule = CycleSchedule(100.0, 5.0, ramp_s=1.0)
    assert schedule.ramp_in(0.0) == 0.0 and schedule.ramp_in(0.5) == 0.5
    assert schedule.ramp_in(1.0) == schedule.ramp_in(3.0) == 1.0
    assert CycleSchedule(100.0, 5.0).ramp_in(0.0) == 1.0  # no ramp
    fractions = [schedule.ramp_out_fraction(k * 0.01) for k in range(100)]
    assert fractions[0] == pytest.approx(0.99) and fractions[99] == 0.0
    assert schedule.ramp_out_fraction(0.986) == 0.0  # under half a period left: done
    assert all(a >= b for a, b in itertools.pairwise(fractions))


def test_the_slew_limit_follows_a_late_cycle_up_to_two_periods() -> None:
    schedule = CycleSchedule(100.0, 1.0)
    assert schedule.slew_period_s(5, None) == 0.01
    assert schedule.slew_period_s(5, 0.01 + 1e-17) == 0.01  # float sums are on time
    assert schedule.slew_period_s(5, 0.004) == 0.01  # early never tightens the budget
    assert schedule.slew_period_s(5, 0.015) == 0.015
    assert schedule.slew_period_s(5, 1.0) == MAX_SLEW_PERIODS * 0.01
    assert schedule.slew_period_s(1, 0.015) == 0.01  # cycle 0 also held the time to connect


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"rate_hz": 0.0}, "rate"),
        ({"rate_hz": math.inf}, "rate"),
        ({"duration_s": 0.0}, "duration"),
        ({"duration_s": math.nan}, "duration"),
        ({"ramp_s": -1.0}, "ramp"),
        ({"rate_hz": 300.0, "timestep_s": 0.002}, "whole number of 0.002 s physics steps"),
    ],
)
def test_a_schedule_that_cannot_run_says_which_part(kwargs: dict[str, float], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        CycleSchedule(**kwargs)  # type: ignore[arg-type]
