"""The rate a bus can hold: the model against servo-families.md §5 (12 servos, 1 Mbps, read
position+speed+load L = 6, goal write L = 2) and the robot files' own settings."""

from __future__ import annotations

import os
import pty
from pathlib import Path

import pytest

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.backends.chain.rate import (
    RateTooHighError,
    check_rate,
    cycle_budget,
    usb_tail_s,
)
from snakebot.config import load_robot
from snakebot.errors import ConfigError
from snakebot.families import family_named
from tests.conftest import edit_robot

P1 = family_named("dynamixel-p1")
P2 = family_named("dynamixel-p2")


def test_ax_one_read_per_servo_pays_twelve_usb_tails() -> None:
    budget = cycle_budget(P1, "read", 12, 6, 2, 1_000_000, 0.0)
    assert budget.wire_s == pytest.approx(2.84e-3)  # 2.40 ms of reads + 0.44 ms sync write
    assert budget.round_trips == 12
    assert budget.cycle_s == pytest.approx(14.84e-3)  # §5: ≈ 14.8 ms
    assert budget.max_rate_hz == pytest.approx(67.4, abs=0.1)
    factory = cycle_budget(P1, "read", 12, 6, 2, 1_000_000, 500e-6)
    assert factory.cycle_s == pytest.approx(20.84e-3)  # + 12 x 500 µs Return Delay Time


def test_mx_bulk_read_pays_one_usb_tail_and_a_return_delay_per_servo() -> None:
    budget = cycle_budget(P1, "bulk_read", 12, 6, 2, 1_000_000, 0.0)
    assert budget.wire_s == pytest.approx(2.31e-3)  # 1.87 ms bulk read + 0.44 ms sync write
    assert budget.cycle_s == pytest.approx(3.31e-3)  # §5: ≈ 3.3 ms
    assert cycle_budget(P1, "bulk_read", 12, 6, 2, 1_000_000, 500e-6).cycle_s == pytest.approx(
        9.31e-3
    )  # §5: RDT 250 → ≈ 10 ms ≈ 100 Hz
    slow = cycle_budget(P1, "bulk_read", 12, 6, 2, 57_600, 0.0)
    assert slow.wire_s == pytest.approx(231 * 10 / 57_600)  # §5: the read alone 32 ms


def test_x_fast_sync_read_is_one_reply_for_the_whole_chain() -> None:
    budget = cycle_budget(P2, "fast_sync_read", 12, 10, 4, 1_000_000, 0.0)
    assert budget.turnarounds == 1 and budget.round_trips == 1
    assert budget.wire_s == pytest.approx(276e-6 * 10)
    assert budget.max_rate_hz > 250


def test_a_rate_above_the_ceiling_is_refused_with_the_ceiling_and_the_ways_to_more() -> None:
    budget = cycle_budget(P1, "read", 12, 6, 2, 1_000_000, 500e-6, fastest_baud=1_000_000)
    check_rate(budget, 40.0)
    with pytest.raises(RateTooHighError) as info:
        check_rate(budget, 100.0)
    error = info.value
    assert isinstance(error, ConfigError) and error.source == "rate_hz"
    assert error.max_rate_hz == pytest.approx(48.0, abs=0.1)
    text = str(error)
    assert "at most 48 Hz" in text and "one Read per servo" in text
    assert "12 x 500 µs Return Delay Time" in text
    assert "assumed: an FTDI adapter at latency_timer 1" in text
    assert "return_delay_time_us = 0" in text and "latency_timer" in text
    assert "baud" not in text.split("For more:")[1]  # an AX is at its fastest at 1 Mbps
    assert "split the chain over two adapters" in text


def test_only_remedies_that_help_are_offered() -> None:
    mx = cycle_budget(
        P1, "bulk_read", 12, 6, 2, 57_600, 0.0, 0.0, usb_assumed=False, fastest_baud=3_000_000
    )
    assert mx.remedies() == [
        "a faster baud rate (up to 3000000 bit/s for this model: [bus] baud, written to the "
        "servos by `snakebot config apply`)"
    ]
    done = cycle_budget(
        P2,
        "fast_sync_read",
        12,
        10,
        4,
        4_000_000,
        0.0,
        0.0,
        usb_assumed=False,
        fastest_baud=4_000_000,
    )
    assert done.remedies() == ["a lower rate: this bus is at its fastest settings"]


@pytest.mark.parametrize("name", ["snake8", "snake12"])
def test_the_shipped_robots_hold_their_default_rate_with_room(name: str) -> None:
    backend = ServoChainBackend(load_robot(name), port="/dev/ttyUSB9")
    budget = backend.rate_budget()
    assert budget.return_delay_s == 0.0  # their servo file sets return_delay_time_us = 0
    assert budget.usb_tail_s == 0.001 and budget.usb_assumed
    backend.check_rate(200.0)


def test_the_robot_files_return_delay_counts_and_a_joints_own_wins(config_dir: Path) -> None:
    path = edit_robot(config_dir, "snake12", "[settings]", "[settings]\nreturn_delay_time_us = 100")
    backend = ServoChainBackend(load_robot(path), port="/dev/ttyUSB9")
    assert backend.rate_budget().return_delay_s == pytest.approx(100e-6)
    path = edit_robot(
        config_dir,
        "snake12",
        "servo_id = 7\n",
        "servo_id = 7\nsettings = { return_delay_time_us = 500 }\n",
    )
    backend = ServoChainBackend(load_robot(path), port="/dev/ttyUSB9")
    assert backend.rate_budget().return_delay_s == pytest.approx(500e-6)


def test_a_pty_or_emulator_port_has_no_usb_tail() -> None:
    assert usb_tail_s("dxlemu://snake") == (0.0, False)
    primary, secondary = pty.openpty()
    try:
        assert usb_tail_s(os.ttyname(secondary)) == (0.0, False)
    finally:
        os.close(primary)
        os.close(secondary)
    assert usb_tail_s("/dev/ttyUSB9") == (0.001, True)


STS = family_named("feetech-sts")
SCS = family_named("feetech-scs")


def test_sts_sync_read_costs_what_the_reference_note_counts() -> None:
    # §5: SYNC_READ request N + 8 = 20 B, 12 replies of 6 + 6 = 144 B; SYNC_WRITE 44 B.
    budget = cycle_budget(STS, "sync_read", 12, 6, 2, 1_000_000, 0.0)
    assert budget.wire_s == pytest.approx((20 + 144 + 44) * 10e-6)
    assert (budget.turnarounds, budget.round_trips) == (12, 1)
    assert budget.max_rate_hz == pytest.approx(1 / 3.08e-3, rel=1e-3)  # §5: ≈ 3 ms, ≈ 330 Hz
    factory = cycle_budget(STS, "sync_read", 12, 6, 2, 1_000_000, 500e-6)
    assert factory.cycle_s == pytest.approx(9.08e-3)  # LeRobot's factory 500 µs a reply
    # SCS has no SYNC_READ: one READ per servo, a USB tail each, as an AX-12A.
    with pytest.raises(ValueError, match="feetech-scs has no sync read"):
        cycle_budget(SCS, "sync_read", 12, 6, 2, 1_000_000, 0.0)
    assert cycle_budget(SCS, "read", 12, 6, 2, 1_000_000, 0.0).round_trips == 12


def test_the_sts3215_snake_is_budgeted_from_its_own_read_and_settings() -> None:
    robot = load_robot("snake12-sts3215")
    budget = ServoChainBackend(robot, port="/dev/ttyUSB0").rate_budget()
    # Present Position, Speed and Current: one 15-byte block (56..70) by one Sync Read, no
    # Return Delay (the servo file writes 0), one assumed 1 ms USB tail.
    assert (budget.family, budget.method, budget.return_delay_s) == (STS, "sync_read", 0.0)
    assert budget.wire_s == pytest.approx((20 + 12 * 21 + 44) * 10e-6)
    assert budget.max_rate_hz == pytest.approx(240.4, abs=0.1)
    check_rate(budget, 200.0)
    with pytest.raises(RateTooHighError, match="at most 240 Hz"):
        check_rate(budget, 500.0)
