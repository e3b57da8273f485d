"""Connect: the chain report, the EEPROM checks, the settings warnings, faults found at connect."""

from __future__ import annotations

import warnings

import pytest

from snakebot.backends.chain.faults import (
    ChainMismatchError,
    ExtraServosWarning,
    HardwareFaultError,
    ServoSettingsError,
    ServoSettingsWarning,
)
from snakebot.emulation import HardwareError, registered
from tests.integration.backends.chain.conftest import Bench, make_bench, robot_variant


def test_connect_reads_the_chain_and_turns_torque_on(bench: Bench) -> None:
    backend = bench.backend()
    with warnings.catch_warnings():
        warnings.simplefilter("error", ServoSettingsWarning)
        backend.connect()
    try:
        assert backend.fast_read
        assert backend.torque_enabled
        assert all(s.torque_enabled for s in bench.chain.servos)
        gains = [(s.peek("position_p_gain"), s.peek("position_d_gain")) for s in bench.chain.servos]
        assert set(gains) == {(640, 4000)}  # snake12's [gains]
    finally:
        backend.close()
    assert not backend.bus.is_open


def test_missing_unexpected_and_mismatched_servos_are_all_reported(bench: Bench) -> None:
    bench.chain.silence(5)
    bench.chain.remove(bench.servo(7))
    bench.add(7, "XM430-W350")
    bench.add(20)
    backend = bench.backend()
    with pytest.raises(ChainMismatchError) as info:
        backend.connect()
    error = info.value
    assert error.missing == (5,)
    assert error.unexpected == (20,)
    assert error.mismatched == {7: (1020, 1060)}
    assert error.servo_ids == (5, 7)
    text = str(error)
    assert "missing servo ID(s) 5" in text
    assert "servo 7 is a XM430-W350, the config expects a XL430-W250" in text
    assert "unexpected servo ID(s) on the bus: 20 (XL430-W250)" in text
    assert not backend.bus.is_open
    assert not any(s.torque_enabled for s in bench.chain.servos)


def test_eeprom_settings_that_break_the_backend_refuse_to_connect(bench: Bench) -> None:
    bench.servo(3).poke("operating_mode", 4)
    bench.servo(4).poke("drive_mode", 1)
    bench.servo(9).poke("max_position_limit", 3000)  # joint limit 1.5 rad is tick 3025
    backend = bench.backend()
    with pytest.raises(ServoSettingsError) as info:
        backend.connect()
    problems = info.value.problems
    assert len(problems) == 3
    assert problems[0].startswith("servo 3: Operating Mode is 4")
    assert problems[1].startswith("servo 4: Drive Mode has the reverse bit")
    assert problems[2].startswith("servo 9: Min/Max Position Limit 0..3000")
    assert not any(s.torque_enabled for s in bench.chain.servos)


def test_default_return_delay_warns_with_the_fix() -> None:
    chain = make_bench(range(1, 13), return_delay=250)
    with registered(chain) as url:
        backend = Bench(chain, url).backend()
        with pytest.warns(ServoSettingsWarning, match=r"Return Delay Time up to 500 µs"):
            backend.connect()
        backend.close()


def test_latched_hardware_error_fails_connect_with_the_reboot_command(bench: Bench) -> None:
    bench.chain.latch_hardware_error(6, HardwareError.OVERHEATING)
    backend = bench.backend()
    with pytest.raises(HardwareFaultError) as info:
        backend.connect()
    assert info.value.servo_id == 6
    assert info.value.flags == ("overheating",)
    assert f"snakebot servo reboot --port {bench.url} --id 6" in str(info.value)


def test_a_tripped_watchdog_from_a_dead_session_is_cleared(bench: Bench) -> None:
    first = bench.backend()
    first.connect()
    bench.chain.advance(0.5)  # the host "dies": no packets for 500 ms
    assert all(s.watchdog_tripped for s in bench.chain.servos)
    first.bus.close()  # the process is gone, no stop ramp
    first.interrupts.__exit__(None, None, None)  # and its signal handlers with it
    second = bench.backend()
    second.connect()
    try:
        assert not any(s.watchdog_tripped for s in bench.chain.servos)
        assert {s.peek("bus_watchdog") for s in bench.chain.servos} == {5}
    finally:
        second.close()


def test_servos_the_robot_does_not_name_refuse_connect_naming_them_and_the_option(
    bench: Bench,
) -> None:
    backend = bench.backend(robot_variant("snake8", ramp_s=0.2))  # 8 servos; the bus holds 12
    with pytest.raises(ChainMismatchError) as info:
        backend.connect()
    error = info.value
    assert error.unexpected == (9, 10, 11, 12)
    assert error.servo_ids == (9, 10, 11, 12)
    assert "unexpected servo ID(s) on the bus: 9 (XL430-W250), 10" in str(error)
    assert "(backend option allow_extra_servos)" in str(error)  # the CLI names its flag
    assert not any(s.torque_enabled for s in bench.chain.servos)
    assert not backend.bus.is_open


def test_extra_servos_said_to_be_expected_are_left_alone(bench: Bench) -> None:
    backend = bench.backend(robot_variant("snake8", ramp_s=0.2), allow_extra_servos=True)
    with pytest.warns(ExtraServosWarning, match=r"servo ID\(s\) 9, 10, 11, 12 are on the bus"):
        backend.connect()
    try:
        assert [s.torque_enabled for s in bench.chain.servos] == [True] * 8 + [False] * 4
    finally:
        backend.close()
    assert {s.peek("bus_watchdog") for s in bench.chain.servos} == {0}


def test_connect_costs_one_broadcast_ping_window_of_bus_time(bench: Bench) -> None:
    start_s = bench.chain.now_s
    backend = bench.backend()
    backend.connect()
    took_s = bench.chain.now_s - start_s
    backend.close()
    # The SDK's broadcast ping waits its whole window (3 ms per possible ID, ~0.8 s at 1 Mbps);
    # everything else in connect is a few ms of bus time.
    assert took_s < 0.9
