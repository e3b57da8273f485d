"""Gait-based compliance on the twin's pegs: the same serpenoid with and without it.

On a peg field where the gait without compliance jams (servos held at over half their stall
torque, not moving, for most of two servo-seconds), the compliant gait gives way, window by
window: the stall time falls by more than half and the peak torque by a third, and the snake
keeps over 80 % of its speed (issue 25's bar; docs/compliance.md has the whole table).
"""

from __future__ import annotations

import pytest

from tools.bench_compliance import run_case

JAMMED = "pegs:density=100,seed=1"
DURATION_S = 8.0  # the jam begins after about 5 s of gait time


@pytest.mark.slow
def test_compliance_halves_the_stall_and_keeps_the_speed_on_pegs() -> None:
    off = run_case("snake8", "serpenoid", JAMMED, DURATION_S, comply=False)
    on = run_case("snake8", "serpenoid", JAMMED, DURATION_S, comply=True)
    assert off["servo_stall_s"] > 1.0, off  # the case is a jam without compliance
    assert on["servo_stall_s"] <= 0.5 * off["servo_stall_s"], (off, on)
    assert on["peak_servo_torque_nm"] < 0.75 * off["peak_servo_torque_nm"], (off, on)
    assert on["speed_m_s"] >= 0.8 * off["speed_m_s"], (off, on)
