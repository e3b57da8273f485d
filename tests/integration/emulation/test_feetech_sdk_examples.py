"""Feetech's own example programs, call for call, against the emulator.

The FTServo_Python examples (ftservo/FTServo_Python: sms_sts/ping.py, read.py, write.py,
sync_read.py, sync_write.py; scscl/ping.py, read.py, write.py, sync_write.py) are not shipped in
the `ftservo-python-sdk` wheel, so each is replayed here as the same sequence of SDK calls with
the same constants (ID 1; group examples IDs 1..10; 1 Mbps; sms_sts goals 4095/0 at speed 60,
acceleration 50; scscl goals 1000/20, time 0, speed 1500, as scscl/reg_write.py has them), and
each `time.sleep` of the example as the same wait. Every call must see COMM_SUCCESS and a zero
status byte, as on a bus; and where an example waits for the move, the servos must be there.
The examples run in process (`dxlemu://` through `EmulatedScsPortHandler`, virtual time) and
through the stock `PortHandler` on a real pseudo-terminal.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import scservo_sdk as scs

from snakebot.emulation import EmulatedChain, make_chain_for_ids, registered
from snakebot.emulation.port_feetech import EmulatedScsPortHandler

BAUD = 1_000_000
GROUP = range(1, 11)  # the group examples' `for scs_id in range(1, 11)`
RETRIES = (scs.COMM_RX_TIMEOUT, scs.COMM_RX_CORRUPT)


def result_of(outcome: Any) -> int:
    """The COMM_* result of an SDK answer: a bare code, (result, error) or (values..., result,
    error)."""
    if isinstance(outcome, int):
        return outcome
    return int(outcome[-2])


def patiently(transaction: Callable[[], Any], seconds: float = 10.0) -> Any:
    """Ask again while a loaded machine makes the pty emulator miss the SDK's 50 ms timeout."""
    deadline = time.monotonic() + seconds
    while True:
        outcome = transaction()
        if result_of(outcome) not in RETRIES or time.monotonic() > deadline:
            return outcome


class Examples:
    """The example programs on an open port; `wait(seconds)` is the examples' time.sleep."""

    def __init__(
        self,
        ph: Any,
        wait: Callable[[float], None],
        ask: Callable[[Callable[[], Any]], Any] = lambda f: f(),
    ) -> None:
        self.ph, self.wait, self.ask = ph, wait, ask

    def ok(self, transaction: Callable[[], Any]) -> Any:
        """Run one SDK call; it must succeed with a zero status byte. Returns its values."""
        outcome = self.ask(transaction)
        result = result_of(outcome)
        assert result == scs.COMM_SUCCESS, self.ph.getTxRxResult(result)
        if not isinstance(outcome, int):
            assert outcome[-1] == 0, self.ph.getRxPacketError(outcome[-1])
            return outcome[:-2]
        return ()

    # ------------------------------------------------------------------ both classes
    def ping(self) -> int:
        (model,) = self.ok(lambda: self.ph.ping(1))
        return int(model)

    def read(self) -> tuple[int, int]:
        position, speed = self.ok(lambda: self.ph.ReadPosSpeed(1))
        return int(position), int(speed)

    # ------------------------------------------------------------------ sms_sts
    def sts_write(self) -> None:
        pause = (4095 - 0) / (60 * 50) + (60 * 50) / (50 * 100) + 0.05
        for goal in (4095, 0):
            self.ok(lambda g=goal: self.ph.WritePosEx(1, g, 60, 50))
            self.wait(pause)
            assert abs(self.read()[0] - goal) <= 8

    def sts_sync_write(self) -> None:
        pause = (4095 - 0) / (60 * 50) + (60 * 50) / (50 * 100) + 0.05
        for goal in (4095, 0):
            for scs_id in GROUP:
                assert self.ph.SyncWritePosEx(scs_id, goal, 60, 50) is True
            assert self.ask(self.ph.groupSyncWrite.txPacket) == scs.COMM_SUCCESS
            self.ph.groupSyncWrite.clearParam()
            self.wait(pause)
            assert all(abs(p - goal) <= 8 for p in self.sts_sync_read())

    def sts_sync_read(self) -> list[int]:
        reader = scs.GroupSyncRead(self.ph, scs.SMS_STS_PRESENT_POSITION_L, 4)
        for scs_id in GROUP:
            assert reader.addParam(scs_id) is True
        assert self.ask(reader.txRxPacket) == scs.COMM_SUCCESS
        positions = []
        for scs_id in GROUP:
            available, error = reader.isAvailable(scs_id, scs.SMS_STS_PRESENT_POSITION_L, 4)
            assert available is True and error == 0
            position = reader.getData(scs_id, scs.SMS_STS_PRESENT_POSITION_L, 2)
            positions.append(self.ph.scs_tohost(position, 15))  # a tick past 0 reads -1
            speed = reader.getData(scs_id, scs.SMS_STS_PRESENT_SPEED_L, 2)
            assert abs(self.ph.scs_tohost(speed, 15)) < 4096
        reader.clearParam()
        return positions

    # ------------------------------------------------------------------ scscl
    def scs_write(self) -> None:
        pause = (1000 - 20) / 1500 + 0.1
        for goal in (1000, 20):
            self.ok(lambda g=goal: self.ph.WritePos(1, g, 0, 1500))
            self.wait(pause)
            assert abs(self.read()[0] - goal) <= 2

    def scs_sync_write(self) -> None:
        pause = (1000 - 20) / 1500 + 0.1
        for goal in (1000, 20):
            for scs_id in GROUP:
                assert self.ph.SyncWritePos(scs_id, goal, 0, 1500) is True
            assert self.ask(self.ph.groupSyncWrite.txPacket) == scs.COMM_SUCCESS
            self.ph.groupSyncWrite.clearParam()
            self.wait(pause)
            for scs_id in GROUP:
                (position,) = self.ok(lambda i=scs_id: self.ph.ReadPos(i))
                assert abs(position - goal) <= 2


STS_EXAMPLES = ("sts_write", "sts_sync_read", "sts_sync_write")
SCS_EXAMPLES = ("scs_write", "scs_sync_write")


@pytest.fixture(params=["STS3215", "SCS0009"])
def in_process(request: pytest.FixtureRequest) -> Iterator[tuple[str, Examples]]:
    model = str(request.param)
    chain = make_chain_for_ids(model, GROUP, BAUD)
    with registered(chain) as url:
        port = EmulatedScsPortHandler(url)
        assert port.openPort() and port.setBaudRate(BAUD)
        ph = scs.sms_sts(port) if model == "STS3215" else scs.scscl(port)
        yield model, Examples(ph, chain.advance)
        port.closePort()


def test_examples_in_process(in_process: tuple[str, Examples]) -> None:
    model, examples = in_process
    assert examples.ping() == {"STS3215": 777, "SCS0009": 1284}[model]
    assert examples.read() == ({"STS3215": 2048, "SCS0009": 512}[model], 0)
    for name in STS_EXAMPLES if model == "STS3215" else SCS_EXAMPLES:
        getattr(examples, name)()


@pytest.mark.pty
@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX")
@pytest.mark.parametrize("model", ["STS3215", "SCS0009"])
def test_examples_through_the_stock_port_handler_on_a_pty(model: str) -> None:
    from snakebot.emulation.pty_server import PtyServer

    chain: EmulatedChain = make_chain_for_ids(model, GROUP, BAUD)
    with PtyServer(chain) as server:
        port = scs.PortHandler(server.device_path)
        assert port.openPort() and port.setBaudRate(BAUD)
        try:
            ph = scs.sms_sts(port) if model == "STS3215" else scs.scscl(port)
            examples = Examples(ph, time.sleep, patiently)
            assert examples.ping() == {"STS3215": 777, "SCS0009": 1284}[model]
            examples.read()
            for name in STS_EXAMPLES if model == "STS3215" else SCS_EXAMPLES:
                getattr(examples, name)()
        finally:
            port.closePort()


@pytest.mark.pty
@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX")
def test_sms_sts_examples_on_emulate_snake12_sts3215_pty() -> None:
    from tests.pty_emulator import emulator

    with emulator("--robot", "snake12-sts3215") as emu:
        assert emu.first["baud"] == BAUD
        assert {s["family"] for s in emu.first["servos"]} == {"feetech-sts"}
        port = scs.PortHandler(emu.port)
        assert port.openPort() and port.setBaudRate(BAUD)
        try:
            examples = Examples(scs.sms_sts(port), time.sleep, patiently)
            assert examples.ping() == 777
            examples.read()
            for name in STS_EXAMPLES:
                getattr(examples, name)()
        finally:
            port.closePort()


@pytest.mark.pty
@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX")
def test_emulate_state_file_keeps_what_lock_0_saved_and_not_what_lock_1_left(
    tmp_path: Path,
) -> None:
    """The EEPROM lock as a user meets it: an ID written between unLockEprom and LockEprom is
    there after the emulator restarts from its state file; a limit written while locked is not."""
    from tests.pty_emulator import emulator

    state = tmp_path / "servos.json"
    args = ("--robot", "snake12-sts3215", "--state-file", str(state))
    with emulator(*args) as emu:
        port = scs.PortHandler(emu.port)
        assert port.openPort() and port.setBaudRate(BAUD)
        ph = scs.sms_sts(port)
        ok = Examples(ph, time.sleep, patiently).ok
        ok(lambda: ph.unLockEprom(12))
        ok(lambda: ph.write1ByteTxRx(12, scs.SMS_STS_ID, 20))
        ok(lambda: ph.LockEprom(20))
        ok(lambda: ph.write1ByteTxRx(20, 13, 55))  # Maximum Temperature Limit, locked
        assert ok(lambda: ph.read1ByteTxRx(20, 13)) == (55,)
        port.closePort()
    with emulator(*args) as emu:
        assert 20 in emu.first["servo_ids"] and 12 not in emu.first["servo_ids"]
        port = scs.PortHandler(emu.port)
        assert port.openPort() and port.setBaudRate(BAUD)
        ph = scs.sms_sts(port)
        ok = Examples(ph, time.sleep, patiently).ok
        assert ok(lambda: ph.read1ByteTxRx(20, 13)) == (70,)
        port.closePort()
