from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from snakebot.backends.chain.checks import (
    chain_error,
    chain_report,
    check_settings,
    cycle_wire_time_s,
    latency_warning,
    usb_latency_timer_ms,
)
from snakebot.backends.chain.faults import (
    ChainMismatchError,
    HardwareFaultError,
    ServoSettingsError,
    decode_hardware_error,
)
from snakebot.backends.chain.shutdown import ramp_poses, safe_pose
from snakebot.backends.chain.ticks import TickConverter
from snakebot.config import load_robot
from snakebot.errors import BusError, ServoFaultError
from snakebot.families import family_named

IDS = tuple(range(1, 9))


def good_settings() -> dict[int, dict[str, int]]:
    return {
        i: {
            "return_delay_time": 0,
            "drive_mode": 0,
            "operating_mode": 3,
            "min_position_limit": 0,
            "max_position_limit": 4095,
        }
        for i in IDS
    }


@pytest.fixture
def converter() -> TickConverter:
    return TickConverter.for_robot(load_robot("snake8"))


def test_hardware_error_bits_decode_by_name() -> None:
    assert decode_hardware_error(0) == ()
    assert decode_hardware_error(0x24) == ("overheating", "overload")
    assert decode_hardware_error(0x01 | 0x08 | 0x10) == (
        "input_voltage",
        "motor_encoder",
        "electrical_shock",
    )
    assert decode_hardware_error(0x42) == ("bit1", "bit6")


def test_fault_error_names_servo_bits_and_the_reboot_command() -> None:
    error = HardwareFaultError("/dev/ttyUSB0", {7: 0x20, 3: 0x04})
    assert isinstance(error, ServoFaultError)
    assert error.servo_id == 3
    assert error.flags == ("overheating",)
    assert error.faults == {7: 0x20, 3: 0x04}
    text = str(error)
    assert "servo 3" in text and "overheating" in text
    assert "snakebot servo reboot --port /dev/ttyUSB0 --id 3" in text
    assert "servo 7 (overload)" in text


def test_chain_report_lists_missing_unexpected_and_mismatched() -> None:
    found = {1: 1060, 2: 1060, 4: 1020}
    report = chain_report([1, 2, 3, 4], 1060, found, {1: 1060, 2: 1060, 4: 1020, 9: 1060})
    assert not report.ok
    assert report.missing == (3,)
    assert dict(report.unexpected) == {9: 1060}
    assert dict(report.mismatched) == {4: (1020, 1060)}
    error = chain_error("dxl", 1_000_000, report, {1060: "XL430-W250", 1020: "XM430-W350"})
    assert isinstance(error, ChainMismatchError) and isinstance(error, BusError)
    assert error.servo_ids == (3, 4)
    text = str(error)
    assert "missing servo ID(s) 3" in text
    assert "servo 4 is a XM430-W350, the config expects a XL430-W250" in text
    assert "unexpected servo ID(s) on the bus: 9 (XL430-W250)" in text
    assert chain_report([1, 2], 1060, {1: 1060, 2: 1060}).ok


def test_good_settings_pass(converter: TickConverter) -> None:
    assert check_settings(good_settings(), IDS, converter) == ([], [])


def test_settings_that_break_the_backend_are_errors(converter: TickConverter) -> None:
    settings = good_settings()
    settings[2]["operating_mode"] = 4
    settings[3]["drive_mode"] = 1
    settings[5]["min_position_limit"] = 1100  # joint range -1.5 rad is tick 1071
    errors, warnings = check_settings(settings, IDS, converter)
    assert len(errors) == 3 and warnings == []
    assert "servo 2: Operating Mode is 4, needs 3" in errors[0]
    assert "servo 3: Drive Mode has the reverse bit" in errors[1]
    assert "servo 5: Min/Max Position Limit 1100..4095" in errors[2]
    assert "joint 4" in errors[2]
    message = str(ServoSettingsError("dxl", errors))
    assert "snakebot config apply" in message and "servo 5" in message


def test_current_based_position_passes_only_where_the_model_has_it(
    converter: TickConverter,
) -> None:
    settings = good_settings()
    settings[2]["operating_mode"] = 5
    errors, _ = check_settings(settings, IDS, converter)  # XL430: no mode 5
    assert errors == ["servo 2: Operating Mode is 5, needs 3 (position control)"]
    errors, notes = check_settings(settings, IDS, converter, current_position_mode=5)
    assert errors == []
    assert len(notes) == 1 and notes[0].startswith("servo(s) 2 in Operating Mode 5")
    assert "ignore their Min/Max Position Limit" in notes[0]
    settings[3]["operating_mode"] = 4
    errors, _ = check_settings(settings, IDS, converter, current_position_mode=5)
    assert errors == [
        "servo 3: Operating Mode is 4, needs 3 (position control) or 5 (current-based "
        "position control)"
    ]


def test_settings_that_cost_rate_are_warnings(converter: TickConverter) -> None:
    settings = good_settings()
    settings[1]["return_delay_time"] = 250
    settings[4]["return_delay_time"] = 10
    settings[6]["drive_mode"] = 4
    errors, warnings = check_settings(settings, IDS, converter)
    assert errors == []
    assert any("servo 6: Drive Mode 4" in w for w in warnings)
    assert any("Return Delay Time up to 500 µs on servo(s) 1, 4" in w for w in warnings)


def test_without_a_watchdog_alarm_shutdown_must_cover_overload_and_heat() -> None:
    ax = TickConverter.for_robot(load_robot("snake12-ax12a"))
    ids = tuple(range(1, 13))
    # AX-12A: no Operating or Drive Mode register; CW/CCW Angle Limit 0..1023, Alarm Shutdown 36
    settings = {
        i: {
            "return_delay_time": 0,
            "min_position_limit": 0,
            "max_position_limit": 1023,
            "shutdown": 36,
        }
        for i in ids
    }
    assert check_settings(settings, ids, ax, watchdog=False) == ([], [])
    settings[3]["shutdown"] = 4  # overheating only
    settings[5]["min_position_limit"] = settings[5]["max_position_limit"] = 0  # wheel mode
    errors, _ = check_settings(settings, ids, ax, watchdog=False)
    assert len(errors) == 2
    assert "servo 3: Alarm Shutdown is 4, needs bits 2 and 5" in errors[0]
    assert "servo 5: CW and CCW Angle Limit are both 0, which is wheel mode" in errors[1]
    settings[5]["max_position_limit"] = 1023
    assert check_settings(settings, ids, ax, watchdog=True) == ([], [])  # a watchdog guards it


def test_latency_timer_is_read_through_symlinks(tmp_path: Path) -> None:
    sysfs = tmp_path / "sys"
    (sysfs / "ttyUSB3").mkdir(parents=True)
    (sysfs / "ttyUSB3" / "latency_timer").write_text("16\n")
    device = tmp_path / "ttyUSB3"
    device.touch()
    by_id = tmp_path / "usb-FTDI_U2D2-if00-port0"
    by_id.symlink_to(device)
    assert usb_latency_timer_ms(str(by_id), sysfs) == 16
    assert usb_latency_timer_ms(str(tmp_path / "ttyACM0"), sysfs) is None
    assert usb_latency_timer_ms("dxlemu://bus", sysfs) is None


def test_latency_warning_gives_the_cap_and_the_fix() -> None:
    assert latency_warning("/dev/ttyUSB0", 1, 0.002) is None
    text = latency_warning("/dev/ttyUSB0", 16, 0.002)
    assert text is not None
    assert "16 ms" in text and "56 Hz" in text
    assert "echo 1 | sudo tee /sys/bus/usb-serial/devices/ttyUSB0/latency_timer" in text


def test_wire_time_matches_the_reference_tables() -> None:
    # reference/performance.md Table 7a/7b: N=16, 4 Mbps, RDT 0, 10-byte read
    p2 = family_named("dynamixel-p2")
    assert cycle_wire_time_s(p2, "fast_sync_read", 16, 10, 4_000_000) == (pytest.approx(890e-6), 1)
    assert cycle_wire_time_s(p2, "sync_read", 16, 10, 4_000_000) == (pytest.approx(1150e-6), 16)
    assert cycle_wire_time_s(p2, "fast_sync_read", 8, 10, 1_000_000)[0] == pytest.approx(1960e-6)


def test_wire_time_of_protocol_1_matches_servo_families_section_5() -> None:
    # 12 servos, 1 Mbps, read L = 6, goal write L = 2: 12 Reads 2.40 ms, Bulk Read 1.87 ms,
    # Sync Write 0.44 ms
    p1 = family_named("dynamixel-p1")
    assert cycle_wire_time_s(p1, "read", 12, 6, 1_000_000, write_bytes=2) == (
        pytest.approx(2.84e-3),
        12,
    )
    assert cycle_wire_time_s(p1, "bulk_read", 12, 6, 1_000_000, write_bytes=2) == (
        pytest.approx(2.31e-3),
        12,
    )


def test_latency_warning_counts_one_timer_per_reply_turnaround() -> None:
    text = latency_warning("/dev/ttyUSB0", 16, 0.00284, turnarounds=12)
    assert text is not None and "near 5 Hz" in text


def test_stop_ramp_is_smooth_and_ends_on_the_safe_pose() -> None:
    robot = load_robot("snake8")
    target = safe_pose(robot)
    np.testing.assert_array_equal(target, np.zeros(8))
    start = np.linspace(-1.0, 1.0, 8)
    poses = ramp_poses(start, target, 0.5, rate_hz=100.0)
    assert len(poses) == 50
    assert poses[-1][0] == pytest.approx(0.5)
    np.testing.assert_array_equal(poses[-1][1], target)
    steps = np.diff(np.array([start] + [p for _, p in poses]), axis=0)
    assert np.abs(steps[0]).max() < np.abs(steps[25]).max()  # slow start, faster middle
    assert ramp_poses(start, target, 0.0)[-1][0] == 0.0
