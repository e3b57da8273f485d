"""VirtualServo firmware rules (e-Manual control-table pages; reference §1.4, §2.2-2.4)."""

import math
from dataclasses import replace

import pytest

from snakebot.emulation import HardwareError, VirtualServo
from snakebot.emulation.errors import EmulationError
from snakebot.emulation.protocol import ALERT_BIT, StatusError


def write(servo: VirtualServo, key: str, value: int) -> int:
    register = servo.table[key]
    return servo.write(register.address, register.encode(value))


def read(servo: VirtualServo, key: str) -> int:
    register = servo.table[key]
    error, data = servo.read(register.address, register.size)
    assert error == 0
    return register.decode(data)


@pytest.fixture
def xl430() -> VirtualServo:
    return VirtualServo("XL430-W250", 7, baud=1_000_000)


def test_factory_defaults_and_identity(xl430: VirtualServo) -> None:
    assert read(xl430, "model_number") == 1060 and read(xl430, "firmware_version") == 46
    assert read(xl430, "id") == 7 and read(xl430, "baud_rate") == 3 and xl430.baud == 1_000_000
    assert read(xl430, "return_delay_time") == 250 and xl430.return_delay_s == pytest.approx(500e-6)
    assert read(xl430, "status_return_level") == 2
    assert [read(xl430, k) for k in ("position_p_gain", "position_i_gain", "position_d_gain")] == [
        640,
        0,
        4000,
    ]
    assert read(xl430, "present_input_voltage") == 111
    assert read(xl430, "present_position") == 2048 == read(xl430, "goal_position")
    assert xl430.ping_params() == bytes([0x24, 0x04, 46])
    assert read(VirtualServo("XM430-W350"), "current_limit") == 1193


def test_invalid_construction_is_refused() -> None:
    with pytest.raises(EmulationError):
        VirtualServo("XL430-W250", 253)
    with pytest.raises(ValueError, match=r"4000000|supported"):
        VirtualServo("XL330-M288", 1, baud=4_500_000)


def test_eeprom_is_locked_while_torque_is_on(xl430: VirtualServo) -> None:
    assert write(xl430, "return_delay_time", 0) == 0
    assert write(xl430, "torque_enable", 1) == 0
    for key, value in (("id", 9), ("operating_mode", 4), ("homing_offset", 10), ("drive_mode", 1)):
        assert write(xl430, key, value) == StatusError.ACCESS, key
    assert read(xl430, "id") == 7 and read(xl430, "operating_mode") == 3
    assert write(xl430, "led", 1) == 0
    assert write(xl430, "torque_enable", 0) == 0
    assert write(xl430, "id", 9) == 0 and xl430.servo_id == 9


def test_read_only_undefined_and_misaligned_writes_are_access_errors(xl430: VirtualServo) -> None:
    assert write(xl430, "present_position", 5) == StatusError.ACCESS
    assert write(xl430, "model_number", 1) == StatusError.ACCESS
    assert xl430.write(66, b"\x00") == StatusError.ACCESS  # reserved gap after LED
    assert xl430.write(117, b"\x00\x00\x00") == StatusError.ACCESS  # middle of Goal Position
    assert xl430.write(5000, b"\x00") == StatusError.ACCESS
    assert xl430.read(5000, 4)[0] == StatusError.ACCESS


def test_short_writes_are_data_length_errors(xl430: VirtualServo) -> None:
    assert xl430.write(116, b"\x00\x08") == StatusError.DATA_LENGTH
    assert xl430.write(116, b"") == StatusError.DATA_LENGTH
    assert read(xl430, "goal_position") == 2048


def test_out_of_range_values_are_data_range_errors(xl430: VirtualServo) -> None:
    assert write(xl430, "status_return_level", 3) == StatusError.DATA_RANGE
    assert write(xl430, "id", 253) == StatusError.DATA_RANGE
    assert write(xl430, "position_p_gain", 16384) == StatusError.DATA_RANGE
    assert write(xl430, "operating_mode", 0) == StatusError.DATA_RANGE  # no current mode on XL430
    assert write(xl430, "operating_mode", 2) == StatusError.DATA_RANGE
    assert write(xl430, "baud_rate", 8) == StatusError.DATA_RANGE
    assert write(VirtualServo("XM430-W350"), "operating_mode", 0) == 0


def test_a_multi_item_write_is_all_or_nothing(xl430: VirtualServo) -> None:
    # Torque Enable(64) = 1 and LED(65) = 2 (out of range) in one packet: nothing changes.
    assert xl430.write(64, b"\x01\x02") == StatusError.DATA_RANGE
    assert not xl430.torque_enabled
    assert xl430.write(64, b"\x01\x01") == 0
    assert xl430.torque_enabled and read(xl430, "led") == 1


def test_goals_beyond_their_limits_are_data_limit_errors(xl430: VirtualServo) -> None:
    assert write(xl430, "max_position_limit", 3000) == 0
    assert write(xl430, "goal_position", 3001) == StatusError.DATA_LIMIT
    assert write(xl430, "goal_position", 3000) == 0
    assert write(xl430, "goal_velocity", 266) == StatusError.DATA_LIMIT
    assert write(xl430, "goal_pwm", -886) == StatusError.DATA_RANGE
    assert write(xl430, "operating_mode", 4) == 0
    assert write(xl430, "goal_position", -100_000) == 0  # extended mode ignores the limits


def test_homing_offset_adds_to_present_position(xl430: VirtualServo) -> None:
    assert write(xl430, "homing_offset", 100) == 0
    assert read(xl430, "present_position") == 2148
    assert write(xl430, "homing_offset", 2000) == 0
    assert read(xl430, "present_position") == 2048  # ignored beyond ±1024 in position mode
    assert write(xl430, "operating_mode", 4) == 0
    assert read(xl430, "present_position") == 4048


def test_drive_mode_reverse_flips_position_velocity_and_load_not_the_offset(
    xl430: VirtualServo,
) -> None:
    xl430.state = replace(xl430.state, position_rad=0.5, velocity_rad_s=1.0, effort=0.25)
    forward = [read(xl430, k) for k in ("present_position", "present_velocity", "present_load")]
    assert write(xl430, "drive_mode", 1) == 0
    assert write(xl430, "homing_offset", 10) == 0
    reverse = [read(xl430, k) for k in ("present_position", "present_velocity", "present_load")]
    assert forward == [2048 + 326, 42, 250]
    assert reverse == [2048 - 326 + 10, -42, -250]


def test_bus_watchdog_trips_and_clears_only_with_zero(xl430: VirtualServo) -> None:
    assert write(xl430, "bus_watchdog", 5) == 0  # 100 ms
    xl430.step(0.5)
    assert not xl430.watchdog_tripped  # torque off: not armed
    assert write(xl430, "torque_enable", 1) == 0
    for _ in range(10):
        xl430.step(0.05)
        xl430.note_packet()
    assert not xl430.watchdog_tripped
    assert write(xl430, "goal_position", 3000) == 0
    xl430.step(0.09)
    xl430.step(0.02)
    assert xl430.watchdog_tripped and read(xl430, "bus_watchdog") == -1
    assert read(xl430, "goal_position") == read(xl430, "present_position") != 3000
    assert write(xl430, "goal_position", 2500) == StatusError.DATA_RANGE
    assert write(xl430, "goal_velocity", 0) == StatusError.DATA_RANGE
    assert write(xl430, "bus_watchdog", 3) == StatusError.DATA_RANGE
    assert write(xl430, "bus_watchdog", 0) == 0
    assert not xl430.watchdog_tripped and read(xl430, "bus_watchdog") == 0
    assert write(xl430, "goal_position", 2500) == 0


def test_latched_error_sets_alert_forces_torque_off_and_needs_reboot(xl430: VirtualServo) -> None:
    assert write(xl430, "torque_enable", 1) == 0
    xl430.latch_error(HardwareError.OVERLOAD)
    assert not xl430.torque_enabled
    assert xl430.status_error() == ALERT_BIT
    assert xl430.status_error(StatusError.ACCESS) == ALERT_BIT | StatusError.ACCESS
    assert read(xl430, "hardware_error_status") == HardwareError.OVERLOAD
    assert write(xl430, "torque_enable", 1) == StatusError.RESULT_FAIL
    xl430.step(1.0)
    assert xl430.hardware_error == HardwareError.OVERLOAD
    xl430.reboot()
    assert xl430.status_error() == 0 and write(xl430, "torque_enable", 1) == 0


def test_error_outside_the_shutdown_mask_alerts_but_keeps_torque(xl430: VirtualServo) -> None:
    assert write(xl430, "torque_enable", 1) == 0
    xl430.state = replace(xl430.state, input_voltage_v=15.0)
    xl430.step(0.01)
    assert xl430.hardware_error == HardwareError.INPUT_VOLTAGE  # 52 = bits 2, 4, 5 only
    assert xl430.torque_enabled and xl430.status_error() == ALERT_BIT


def test_overheating_is_detected_against_the_temperature_limit(xl430: VirtualServo) -> None:
    assert write(xl430, "torque_enable", 1) == 0
    xl430.state = replace(xl430.state, temperature_c=72.0)
    xl430.step(0.01)
    assert xl430.hardware_error == 0
    xl430.state = replace(xl430.state, temperature_c=73.0)
    xl430.step(0.01)
    assert xl430.hardware_error == HardwareError.OVERHEATING and not xl430.torque_enabled


def test_reboot_resets_ram_keeps_eeprom_and_loses_turns(xl430: VirtualServo) -> None:
    assert write(xl430, "return_delay_time", 0) == 0
    assert write(xl430, "operating_mode", 4) == 0
    assert write(xl430, "led", 1) == 0 and write(xl430, "torque_enable", 1) == 0
    xl430.state = replace(xl430.state, position_rad=2.5 * 2 * math.pi)
    assert read(xl430, "present_position") > 4096 * 2
    xl430.reboot()
    assert not xl430.torque_enabled and read(xl430, "led") == 0
    assert read(xl430, "return_delay_time") == 0 and read(xl430, "operating_mode") == 4
    assert 0 <= read(xl430, "present_position") < 4096
    assert read(xl430, "goal_position") == read(xl430, "present_position")


@pytest.mark.parametrize(
    ("option", "servo_id", "baud_index"), [(0xFF, 1, 1), (0x01, 7, 1), (0x02, 7, 3)]
)
def test_factory_reset_variants(
    xl430: VirtualServo, option: int, servo_id: int, baud_index: int
) -> None:
    assert write(xl430, "return_delay_time", 0) == 0 and write(xl430, "position_p_gain", 99) == 0
    assert xl430.factory_reset(option) == 0
    assert (read(xl430, "id"), read(xl430, "baud_rate")) == (servo_id, baud_index)
    assert read(xl430, "return_delay_time") == 250 and read(xl430, "position_p_gain") == 640


def test_factory_reset_rejects_unknown_options(xl430: VirtualServo) -> None:
    assert xl430.factory_reset(0x03) == StatusError.DATA_RANGE
    assert xl430.servo_id == 7


def test_reg_write_waits_for_action(xl430: VirtualServo) -> None:
    assert xl430.action() == StatusError.INSTRUCTION
    goal = xl430.table["goal_position"]
    assert xl430.reg_write(goal.address, goal.encode(3000)) == 0
    assert read(xl430, "registered_instruction") == 1 and read(xl430, "goal_position") == 2048
    assert xl430.action() == 0
    assert read(xl430, "registered_instruction") == 0 and read(xl430, "goal_position") == 3000
    assert xl430.reg_write(goal.address, goal.encode(5000)) == StatusError.DATA_LIMIT


def test_clear_multi_turn_refuses_while_moving(xl430: VirtualServo) -> None:
    xl430.state = replace(xl430.state, position_rad=7.0, velocity_rad_s=3.0)
    assert xl430.clear(bytes.fromhex("01 44 58 4C 22")) == StatusError.RESULT_FAIL
    xl430.state = replace(xl430.state, velocity_rad_s=0.0)
    assert xl430.clear(bytes.fromhex("01 00 00 00 00")) == StatusError.DATA_RANGE
    assert xl430.clear(bytes.fromhex("01 44 58 4C 22")) == 0
    assert xl430.state.position_rad == pytest.approx(7.0 - 2 * math.pi)


def test_operating_mode_change_resets_profile_and_gains(xl430: VirtualServo) -> None:
    assert write(xl430, "profile_velocity", 50) == 0 and write(xl430, "position_p_gain", 1) == 0
    assert write(xl430, "operating_mode", 1) == 0
    assert read(xl430, "profile_velocity") == 0 and read(xl430, "position_p_gain") == 640


def test_command_carries_the_position_gains_and_changes_with_them(xl430: VirtualServo) -> None:
    first = xl430.command()
    assert first.position_gains == (640, 0, 4000) and xl430.command() is first  # cached
    assert write(xl430, "position_d_gain", 300) == 0 and write(xl430, "position_i_gain", 5) == 0
    assert xl430.command().position_gains == (640, 5, 300)


def test_indirect_addresses_map_data_bytes(xl430: VirtualServo) -> None:
    first = xl430.table["indirect_address_1"].address
    for k in range(4):
        assert xl430.write(first + 2 * k, (116 + k).to_bytes(2, "little")) == 0
    data_1 = xl430.table["indirect_data_1"].address
    assert xl430.read(data_1, 4) == (0, (2048).to_bytes(4, "little"))
    assert xl430.write(data_1, (2500).to_bytes(4, "little")) == 0
    assert read(xl430, "goal_position") == 2500
    assert xl430.write(data_1, (9000).to_bytes(4, "little")) == StatusError.DATA_LIMIT


def test_torque_on_by_goal_update_drive_mode_bit(xl430: VirtualServo) -> None:
    assert write(xl430, "drive_mode", 0x08) == 0
    assert write(xl430, "goal_position", 2100) == 0
    assert xl430.torque_enabled


def test_realtime_tick_counts_milliseconds_and_wraps(xl430: VirtualServo) -> None:
    xl430.step(1.234)
    assert read(xl430, "realtime_tick") == 1234
    xl430.step(32.768)
    assert read(xl430, "realtime_tick") == 1234
