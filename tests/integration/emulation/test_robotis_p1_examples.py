"""ROBOTIS's Protocol 1.0 example programs, call for call, against the emulator.

The DynamixelSDK's Python examples (python/tests/protocol1_0: ping, read_write, sync_write,
bulk_read, factory_reset; the e-Manual's "Python Protocol 1.0" sample-code pages show them) are
not shipped in the SDK wheel, so each is replayed here as the same sequence of SDK calls with
the same constants, through the stock `dynamixel_sdk`, and must see no communication or packet
error. Two servos the examples name: an MX-28 with its Protocol 1.0 firmware (addresses 24/30/36/
46, two bytes, in process), and X-series servos set to Protocol 1.0 (64/116/132/122, four bytes,
as the SDK's current bulk_read example has it) served by `snakebot emulate --protocol 1 --pty`.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import dynamixel_sdk as dxl
import pytest

from snakebot.emulation import make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from tests.pty_emulator import emulator, patient

MIN_GOAL, MAX_GOAL = 100, 4000  # DXL_MINIMUM/MAXIMUM_POSITION_VALUE
THRESHOLD = 20  # DXL_MOVING_STATUS_THRESHOLD
IDS = (1, 2)  # DXL1_ID, DXL2_ID


@dataclass(frozen=True)
class Table:
    """The example's control-table constants for one servo family."""

    torque: int
    goal: int
    present: int
    moving: int
    baud: int
    width: int  # LEN_..._GOAL_POSITION / PRESENT_POSITION
    factory_baudnum: int  # what a factory reset leaves in the Baud Rate register
    baudnum_1m: int  # NEW_BAUDNUM: 1 Mbps


MX = Table(24, 30, 36, 46, 4, 2, 34, 1)
X_SERIES = Table(64, 116, 132, 122, 8, 4, 1, 3)


class Example:
    """One example's SDK calls on an open port; every call must succeed without an error."""

    def __init__(
        self,
        port: Any,
        table: Table,
        settle: Callable[[], None],
        *,
        ask: Callable[[Callable[[], Any]], Any] = lambda f: f(),
    ) -> None:
        self.port, self.t, self.settle, self.ask = port, table, settle, ask
        self.ph = dxl.PacketHandler(1.0)

    def ok(self, outcome: Any) -> Any:
        """The value of a (value, result, error) or (result, error) answer; fails otherwise."""
        *value, result, error = outcome if isinstance(outcome, tuple) else (outcome, 0)
        assert result == dxl.COMM_SUCCESS, self.ph.getTxRxResult(result)
        assert error == 0, self.ph.getRxPacketError(error)
        return value[0] if value else None

    def write(self, servo_id: int, address: int, value: int, width: int) -> None:
        call = {1: self.ph.write1ByteTxRx, 2: self.ph.write2ByteTxRx, 4: self.ph.write4ByteTxRx}
        self.ok(self.ask(lambda: call[width](self.port, servo_id, address, value)))

    def read(self, servo_id: int, address: int, width: int) -> int:
        call = {1: self.ph.read1ByteTxRx, 2: self.ph.read2ByteTxRx, 4: self.ph.read4ByteTxRx}
        return int(self.ok(self.ask(lambda: call[width](self.port, servo_id, address))))

    def until_reached(self, goal: int, present: Callable[[], list[int]]) -> None:
        deadline = time.monotonic() + 20.0
        while any(abs(goal - p) > THRESHOLD for p in present()):
            assert time.monotonic() < deadline, "the servos never reached the goal"
            self.settle()

    def ping(self) -> int:
        return int(self.ok(self.ask(lambda: self.ph.ping(self.port, IDS[0]))))

    def read_write(self) -> None:
        t = self.t
        self.write(IDS[0], t.torque, 1, 1)
        for goal in (MIN_GOAL, MAX_GOAL):
            self.write(IDS[0], t.goal, goal, t.width)
            self.until_reached(goal, lambda: [self.read(IDS[0], t.present, t.width)])
        self.write(IDS[0], t.torque, 0, 1)

    def sync_write(self) -> None:
        t = self.t
        for servo_id in IDS:
            self.write(servo_id, t.torque, 1, 1)
        writer = dxl.GroupSyncWrite(self.port, self.ph, t.goal, t.width)
        for goal in (MIN_GOAL, MAX_GOAL):
            for servo_id in IDS:
                assert writer.addParam(servo_id, goal.to_bytes(t.width, "little"))
            self.ok((writer.txPacket(), 0))
            writer.clearParam()
            self.until_reached(goal, lambda: [self.read(i, t.present, t.width) for i in IDS])
        for servo_id in IDS:
            self.write(servo_id, t.torque, 0, 1)

    def bulk_read(self) -> None:
        t = self.t
        for servo_id in IDS:
            self.write(servo_id, t.torque, 1, 1)
        reader = dxl.GroupBulkRead(self.port, self.ph)
        assert reader.addParam(IDS[0], t.present, t.width)
        assert reader.addParam(IDS[1], t.moving, 1)

        def present() -> list[int]:
            # The example calls reader.txRxPacket(); in dynamixel_sdk 4.1 that passes the
            # Protocol 1.0 handler's bulkReadTx one argument too many (a TypeError before any
            # byte is sent), so the same request goes out through the handler itself.
            reader.makeParam()

            def transaction() -> tuple[int, int]:
                sent = self.ph.bulkReadTx(self.port, reader.param, 3 * len(IDS))
                return (reader.rxPacket() if sent == dxl.COMM_SUCCESS else sent), 0

            self.ok(self.ask(transaction))
            assert reader.isAvailable(IDS[0], t.present, t.width)
            assert reader.isAvailable(IDS[1], t.moving, 1)
            reader.getData(IDS[1], t.moving, 1)
            return [reader.getData(IDS[0], t.present, t.width)]

        for goal in (MIN_GOAL, MAX_GOAL):
            for servo_id in IDS:
                self.write(servo_id, t.goal, goal, t.width)
            self.until_reached(goal, present)
        reader.clearParam()
        for servo_id in IDS:
            self.write(servo_id, t.torque, 0, 1)

    def factory_reset(self) -> None:
        t = self.t
        self.ok(self.ask(lambda: self.ph.factoryReset(self.port, IDS[0])))
        self.settle()  # "Wait for reset..."
        assert self.port.setBaudRate(57600)  # FACTORYRST_DEFAULTBAUDRATE
        assert self.read(IDS[0], t.baud, 1) == t.factory_baudnum
        self.write(IDS[0], t.baud, t.baudnum_1m, 1)
        assert self.port.setBaudRate(1_000_000)
        assert self.read(IDS[0], t.baud, 1) == t.baudnum_1m


@pytest.fixture
def mx28() -> Iterator[Example]:
    chain = make_chain_for_ids("MX-28", IDS, 1_000_000)
    with registered(chain) as url:
        port = EmulatedPortHandler(url)
        assert port.openPort() and port.setBaudRate(1_000_000)
        yield Example(port, MX, lambda: chain.advance(0.05))
        port.closePort()


def test_ping_mx28(mx28: Example) -> None:
    assert mx28.ping() == 29


@pytest.mark.parametrize("name", ["read_write", "sync_write", "bulk_read", "factory_reset"])
def test_examples_mx28(mx28: Example, name: str) -> None:
    getattr(mx28, name)()


@pytest.mark.pty
@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX")
def test_examples_on_emulate_protocol_1_pty() -> None:
    with emulator("--protocol", "1") as emu:
        assert emu.first["baud"] == 1_000_000
        port = dxl.PortHandler(emu.port)
        assert port.openPort() and port.setBaudRate(1_000_000)
        try:
            example = Example(port, X_SERIES, lambda: time.sleep(0.05), ask=patient)
            assert example.ping() == 1060
            for name in ("read_write", "sync_write", "bulk_read", "factory_reset"):
                getattr(example, name)()
        finally:
            port.closePort()
