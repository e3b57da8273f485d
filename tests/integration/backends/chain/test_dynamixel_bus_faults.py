"""Faults injected in the emulated chain reach the caller as typed errors, never as zeros."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from snakebot.backends.chain.bus import ServoBus
from snakebot.backends.chain.faults import SyncReadError
from snakebot.emulation import HardwareError
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.errors import BusError, ServoFaultError
from tests.integration.backends.chain.conftest import BAUD, Bench

ANGLES = np.linspace(-1.0, 1.0, 12)
STATE_KEYS = ("present_load", "present_velocity", "present_position")


def place(bench: Bench) -> None:
    for servo_id, angle in zip(range(1, 13), ANGLES, strict=True):
        servo = bench.servo(servo_id)
        servo.state = dataclasses.replace(servo.state, position_rad=float(angle))


@pytest.fixture
def bus(bench: Bench) -> ServoBus:
    bus = ServoBus(bench.url, BAUD, port_handler_factory=EmulatedPortHandler)
    bus.open()
    return bus


def test_hardware_error_raises_a_fault_naming_servo_and_bit(bench: Bench) -> None:
    with bench.backend() as backend:
        backend.read_state()
        bench.chain.latch_hardware_error(8, HardwareError.OVERLOAD)
        with pytest.raises(ServoFaultError) as info:
            for _ in range(backend.slow_every):
                backend.read_state()
        assert info.value.servo_id == 8
        assert info.value.flags == ("overload",)
        assert f"snakebot servo reboot --port {bench.url} --id 8" in str(info.value)
    assert not bench.servo(8).torque_enabled  # the fault took torque off; reboot clears it
    bus = backend.bus
    bus.open()
    bus.reboot(8)
    assert bus.read(8, "hardware_error_status") == 0


def test_silenced_servo_is_retried_then_named(bench: Bench, bus: ServoBus) -> None:
    bench.chain.silence(6)
    with pytest.raises(BusError) as info:
        bus.read(6, "present_position")
    assert info.value.servo_ids == (6,)
    assert "There is no status packet" in str(info.value)
    assert bus.retry_counts[6] == 2
    with pytest.raises(BusError, match="ping"):
        bus.ping(6)
    assert bus.ping_all([5, 6, 7]) == {5: 1060, 7: 1060}


@pytest.mark.parametrize("fast", [True, False])
def test_corrupt_reply_is_retried(bench: Bench, bus: ServoBus, fast: bool) -> None:
    place(bench)
    bench.chain.corrupt_replies(3, next_n=1)
    values = bus.sync_read(STATE_KEYS, list(range(1, 13)), fast=fast)
    assert bus.group_retries == 1
    assert [values[i]["present_position"] for i in range(1, 13)] == [
        bench.servo(i).peek("present_position") for i in range(1, 13)
    ]
    bench.chain.corrupt_replies(3, next_n=1)
    assert bus.read(3, "present_position") == bench.servo(3).peek("present_position")
    assert bus.retry_counts[3] == 1


@pytest.mark.parametrize("fast", [True, False])
def test_one_missing_servo_never_publishes_zeros(bench: Bench, fast: bool) -> None:
    place(bench)
    with bench.backend() as backend:
        backend.fast_read = fast
        before = backend.read_state()
        bench.chain.silence(5)
        with pytest.raises(SyncReadError) as info:
            backend.read_state()
        error = info.value
        assert error.missing_ids == (5,)
        assert "servo(s) 5" in str(error)
        assert sorted(error.partial) == [i for i in range(1, 13) if i != 5]
        for servo_id, values in error.partial.items():
            assert values["present_position"] == bench.servo(servo_id).peek("present_position")
            assert values["present_position"] != 0
        assert backend.bus.retry_counts[5] == backend.bus.retries
        bench.chain.silence(5, False)
        bench.chain.drop_replies(5, next_n=1)  # a single lost reply: retried, real values
        after = backend.read_state()
    np.testing.assert_allclose(after.position_rad, before.position_rad, atol=1e-3)
    assert np.all(after.position_rad != -np.pi)  # a zero tick would read as -pi
