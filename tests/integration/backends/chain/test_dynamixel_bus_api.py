"""The bus API by name over the emulator: blocks, bulk read, scans, reboot, factory reset; a pty."""

from __future__ import annotations

import dataclasses
import os

import numpy as np
import pytest

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.backends.chain.bus import ServoBus
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.types import JointCommand
from tests.integration.backends.chain.conftest import BAUD, Bench, make_bench, robot_variant


@pytest.fixture
def bus(bench: Bench) -> ServoBus:
    bus = ServoBus(bench.url, BAUD, port_handler_factory=EmulatedPortHandler)
    bus.open()
    return bus


def test_registers_by_name_with_signed_values(bench: Bench, bus: ServoBus) -> None:
    servo = bench.servo(2)
    servo.state = dataclasses.replace(servo.state, position_rad=-4.0)  # below tick 0: negative
    assert bus.read(2, "present_position") == servo.peek("present_position") < 0
    bus.write(2, "position_p_gain", 1234)
    assert servo.peek("position_p_gain") == 1234
    assert bus.read_block(2, ("position_d_gain", "position_p_gain")) == {
        "position_d_gain": 4000,
        "position_p_gain": 1234,
    }


def test_sync_write_of_a_contiguous_block(bench: Bench, bus: ServoBus) -> None:
    keys = ("position_d_gain", "position_i_gain", "position_p_gain")
    bus.sync_write(keys, {1: (10, 20, 30), 2: (11, 21, 31)})
    assert bus.sync_read(keys, [1, 2]) == {
        1: {"position_d_gain": 10, "position_i_gain": 20, "position_p_gain": 30},
        2: {"position_d_gain": 11, "position_i_gain": 21, "position_p_gain": 31},
    }
    with pytest.raises(ValueError, match="not contiguous"):
        bus.sync_write(("position_p_gain", "goal_position"), {1: (1, 2)})


def test_bulk_read_takes_a_different_block_per_servo(bench: Bench, bus: ServoBus) -> None:
    values = bus.bulk_read(
        {1: "present_temperature", 4: ("model_number", "firmware_version"), 7: "present_position"}
    )
    assert values[1] == {"present_temperature": 30}
    assert values[4] == {"model_number": 1060, "firmware_version": 46}
    assert values[7] == {"present_position": 2048}


def test_broadcast_ping_finds_every_servo(bench: Bench, bus: ServoBus) -> None:
    found = bus.broadcast_ping()
    assert sorted(found) == list(range(1, 13))
    assert found[3] == (1060, 46)


def test_factory_reset_keeps_id_and_baud(bench: Bench, bus: ServoBus) -> None:
    bus.write(5, "return_delay_time", 17)
    bus.factory_reset(5)
    assert bus.ping(5) == 1060
    assert bus.read(5, "return_delay_time") == 250  # the factory default


@pytest.mark.pty
@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX")
def test_stock_port_handler_over_a_pseudo_terminal() -> None:
    from snakebot.emulation.pty_server import PtyServer

    chain = make_bench(range(1, 13))
    with PtyServer(chain) as server:
        backend = ServoChainBackend(
            robot_variant(ramp_s=0.05), port=server.device_path, baud=BAUD
        )  # dynamixel_sdk.PortHandler on a real tty
        with backend:
            backend.send_command(JointCommand(np.full(12, 0.2)))
            for _ in range(30):
                backend.advance(0.01)
            state = backend.read_state()
        np.testing.assert_allclose(state.position_rad, 0.2, atol=0.02)
