"""Emulator support for bring-up: fresh servos, the EEPROM state file, scrambled settings."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from snakebot.backends.chain.checks import check_settings
from snakebot.backends.chain.ticks import TickConverter
from snakebot.config import load_robot
from snakebot.emulation.bench import ServoBench, new_servo, robot_servos, scramble
from snakebot.emulation.chain import EmulatedChain
from snakebot.emulation.errors import EmulationError
from snakebot.emulation.state_file import load_state

MODEL = "XL430-W250"


def test_fresh_servos_arrive_with_factory_settings_one_at_a_time() -> None:
    bench = ServoBench(EmulatedChain(), MODEL, fresh=2)
    assert (bench.waiting, bench.chain.servos) == (2, ())
    first = bench.plug()
    assert (first.servo_id, first.baud, first.serial_number) == (1, 57600, 1)
    assert (first.peek("return_delay_time"), first.peek("status_return_level")) == (250, 2)
    assert first.peek("position_p_gain") == 640
    assert abs(first.state.position_rad) <= 0.3
    assert first.peek("goal_position") == first.peek("present_position")
    assert bench.plug().serial_number == 2 and bench.waiting == 0
    with pytest.raises(EmulationError, match="all 2 fresh servos are plugged in"):
        bench.plug()


def test_fresh_units_differ_in_timing_and_shaft_angle() -> None:
    a, b = new_servo(MODEL, 1), new_servo(MODEL, 2)
    assert a.processing_time_s != b.processing_time_s
    assert a.peek("present_position") != b.peek("present_position")


def test_eeprom_survives_a_power_cycle_and_a_restart(tmp_path: Path) -> None:
    state = tmp_path / "state.json"
    bench = ServoBench(EmulatedChain(), MODEL, fresh=3, state_path=state)
    servo = bench.plug()
    servo.poke("id", 9)
    servo.poke("return_delay_time", 0)
    servo.poke("position_p_gain", 100)  # RAM: lost at power-off
    bench.power_cycle()
    assert (servo.servo_id, servo.peek("position_p_gain")) == (9, 640)
    assert bench.save() is False  # nothing changed since the power cycle saved it
    data = json.loads(state.read_text())
    assert data["format"] == "snakebot-emulator-state" and list(data["servos"]) == ["1"]
    again = ServoBench(EmulatedChain(), MODEL, fresh=3, state_path=state)
    (back,) = again.chain.servos
    assert (back.servo_id, back.peek("return_delay_time"), back.serial_number) == (9, 0, 1)
    assert again.waiting == 2
    assert again.plug().serial_number == 2


def test_a_robot_chain_takes_its_eeprom_from_the_state_file(tmp_path: Path) -> None:
    state = tmp_path / "state.json"
    chain = EmulatedChain(robot_servos(MODEL, [1, 2, 3], 1_000_000), baud=1_000_000)
    chain.servo(2).poke("baud_rate", 1)
    ServoBench(chain, MODEL, state_path=state).save()
    again = EmulatedChain(robot_servos(MODEL, [1, 2, 3], 1_000_000), baud=1_000_000)
    ServoBench(again, MODEL, state_path=state)
    assert [s.baud for s in again.servos] == [1_000_000, 57600, 1_000_000]


def test_unusable_state_files_say_what_is_wrong(tmp_path: Path) -> None:
    path = tmp_path / "state.json"
    path.write_text('{"format": "other"}')
    with pytest.raises(EmulationError, match="not a usable emulator state file"):
        load_state(path)
    good = tmp_path / "ok.json"
    ServoBench(EmulatedChain(robot_servos(MODEL, [1], 57600)), MODEL, state_path=good).save()
    with pytest.raises(EmulationError, match="saved as model 1060, not 1020"):
        ServoBench(EmulatedChain(robot_servos("XM430-W350", [1], 57600)), MODEL, state_path=good)


def test_scramble_gives_settings_the_backend_refuses() -> None:
    robot = load_robot("snake12")
    chain = EmulatedChain(robot_servos(MODEL, robot.servo_ids, 1_000_000), baud=1_000_000)
    scramble(chain, seed=1)
    keys = (
        "return_delay_time",
        "drive_mode",
        "operating_mode",
        "min_position_limit",
        "max_position_limit",
    )
    values = {s.servo_id: {k: s.peek(k) for k in keys} for s in chain.servos}
    errors, _ = check_settings(values, robot.servo_ids, TickConverter.for_robot(robot))
    assert any("reverse bit" in e for e in errors) and any("needs 3" in e for e in errors)
    assert sorted(s.baud for s in chain.servos)[:2] == [57600, 115200]
    assert chain.servo(2).peek("status_return_level") == 1
    assert chain.servo(12).torque_enabled


def test_fresh_and_scrambled_ax12a_servos_keep_to_their_own_table() -> None:
    fresh = new_servo("AX-12A", 1)
    assert (fresh.servo_id, fresh.baud, fresh.protocol) == (1, 1_000_000, 1.0)  # AX factory
    chain = EmulatedChain(robot_servos("AX-12A", range(1, 13), 1_000_000), baud=1_000_000)
    scramble(chain, 3)  # used to look up X-only registers (drive mode, homing offset)
    limits = [(s.peek("min_position_limit"), s.peek("max_position_limit")) for s in chain.servos]
    assert (375, 650) in limits and all(0 <= lo <= hi <= 1023 for lo, hi in limits)
    assert chain.servos[1].peek("status_return_level") == 1
