"""The pty server keeps serving whatever arrives, and a server thread that dies is never silent."""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Iterator

import dynamixel_sdk as dxl
import pytest

from snakebot.emulation import make_chain_for_ids
from tests.pty_emulator import emulator, patient

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]

BAUD = 1_000_000


@pytest.fixture
def sdk_port() -> Iterator[tuple[dxl.PortHandler, dxl.Protocol2PacketHandler]]:
    with emulator("--robot", "snake12") as emu:
        handler = dxl.PortHandler(emu.port)
        assert handler.openPort() and handler.setBaudRate(BAUD)
        yield handler, dxl.PacketHandler(2.0)
        handler.closePort()
        emu.stop()  # asserts a clean exit 0


def test_an_84_byte_fast_sync_read_for_70_ids_does_not_kill_the_emulator(
    sdk_port: tuple[dxl.PortHandler, dxl.Protocol2PacketHandler],
) -> None:
    port, ph = sdk_port
    reader = dxl.GroupSyncRead(port, ph, 0, 1000)  # the reply would be 70 x 1004 bytes
    for servo_id in range(1, 71):
        reader.addParam(servo_id)
    assert reader.fastSyncRead() == dxl.COMM_RX_TIMEOUT
    assert patient(lambda: ph.ping(port, 7)) == (1060, dxl.COMM_SUCCESS, 0)


def test_a_dying_server_thread_is_reported_not_silent() -> None:
    from snakebot.emulation.pty_server import PtyServer, PtyServerCrashedError

    def broken_trace(direction: str, data: bytes) -> None:
        raise ZeroDivisionError("a bug in the server thread")

    server = PtyServer(make_chain_for_ids("XL430-W250", [1], BAUD), trace=broken_trace)
    with pytest.raises(PtyServerCrashedError, match="a bug in the server thread"), server:
        port = dxl.PortHandler(server.device_path)
        assert port.openPort() and port.setBaudRate(BAUD)
        assert dxl.PacketHandler(2.0).ping(port, 1)[1] == dxl.COMM_RX_TIMEOUT
        port.closePort()
        deadline = time.monotonic() + 10.0  # a loaded machine may run the thread late
        while server.failure is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert isinstance(server.failure, ZeroDivisionError)
    assert not any(t.name.startswith("pty-server") for t in threading.enumerate())


def test_emulate_stops_with_the_crash_when_its_server_thread_dies() -> None:
    from snakebot.cli.emulate_cmd import serve_until
    from snakebot.emulation.pty_server import PtyServer, PtyServerCrashedError

    def broken_trace(direction: str, data: bytes) -> None:
        raise ZeroDivisionError("a bug in the server thread")

    ticks: list[int] = []
    server = PtyServer(make_chain_for_ids("XL430-W250", [1], BAUD), trace=broken_trace).start()
    try:
        port = dxl.PortHandler(server.device_path)
        assert port.openPort() and port.setBaudRate(BAUD)
        dxl.PacketHandler(2.0).ping(port, 1)
        port.closePort()
        with pytest.raises(PtyServerCrashedError) as crash:
            serve_until(threading.Event(), server, lambda: ticks.append(1))
        assert isinstance(crash.value.__cause__, ZeroDivisionError)
    finally:
        server.stop()


WATCHDOG, TORQUE, GOAL = 98, 64, 116


def test_a_starved_emulator_reads_what_queued_before_it_judges_the_bus_watchdog() -> None:
    # The emulator process is stopped for 1.5 s (as a loaded machine can starve it) while the
    # host keeps writing goals every 50 ms, well inside the 1 s watchdog: nothing may trip.
    with emulator("--robot", "snake12") as emu:
        port = dxl.PortHandler(emu.port)
        ph = dxl.PacketHandler(2.0)
        assert port.openPort() and port.setBaudRate(BAUD)
        assert patient(lambda: ph.write1ByteTxRx(port, 1, TORQUE, 1)) == (dxl.COMM_SUCCESS, 0)
        armed = patient(lambda: ph.write1ByteTxRx(port, 1, WATCHDOG, 50))  # 50 x 20 ms
        assert armed == (dxl.COMM_SUCCESS, 0)
        writer = dxl.GroupSyncWrite(port, ph, GOAL, 4)
        goal = 2048
        emu.proc.send_signal(signal.SIGSTOP)
        try:
            for _ in range(30):
                goal += 5
                writer.clearParam()
                writer.addParam(1, list(goal.to_bytes(4, "little")))
                assert writer.txPacket() == dxl.COMM_SUCCESS
                time.sleep(0.05)
        finally:
            emu.proc.send_signal(signal.SIGCONT)
        time.sleep(0.2)  # the emulator catches up; still well inside the watchdog period
        watchdog = patient(lambda: ph.read1ByteTxRx(port, 1, WATCHDOG), seconds=0.5)
        assert watchdog == (50, dxl.COMM_SUCCESS, 0)  # not tripped
        assert patient(lambda: ph.read4ByteTxRx(port, 1, GOAL)) == (goal, dxl.COMM_SUCCESS, 0)
        port.closePort()
        emu.stop()
