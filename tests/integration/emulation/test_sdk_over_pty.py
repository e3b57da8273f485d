"""The stock dynamixel_sdk.PortHandler on a real pseudo-terminal served by PtyServer."""

import os
import time
from collections.abc import Iterator
from pathlib import Path

import dynamixel_sdk as dxl
import pytest

from snakebot.emulation import EmulatedChain, EmulationError, make_chain_for_ids
from tests.pty_emulator import patient

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]

BAUD = 1_000_000
IDS = list(range(1, 13))


@pytest.fixture
def served() -> Iterator[tuple[EmulatedChain, str]]:
    from snakebot.emulation.pty_server import PtyServer

    chain = make_chain_for_ids("XL430-W250", IDS, BAUD)
    with PtyServer(chain) as server:
        yield chain, server.device_path


@pytest.fixture
def port(served: tuple[EmulatedChain, str]) -> Iterator[dxl.PortHandler]:
    handler = dxl.PortHandler(served[1])
    assert handler.openPort() and handler.setBaudRate(BAUD)
    yield handler
    handler.closePort()


def test_ping_read_and_sync_read_twelve_servos(port: dxl.PortHandler) -> None:
    ph = dxl.PacketHandler(2.0)
    for servo_id in IDS:
        assert patient(lambda i=servo_id: ph.ping(port, i)) == (1060, dxl.COMM_SUCCESS, 0)
    assert patient(lambda: ph.read2ByteTxRx(port, 4, 144)) == (111, dxl.COMM_SUCCESS, 0)
    reader = dxl.GroupSyncRead(port, ph, 132, 4)
    for servo_id in IDS:
        reader.addParam(servo_id)
    assert patient(reader.txRxPacket) == dxl.COMM_SUCCESS
    assert [reader.getData(i, 132, 4) for i in IDS] == [2048] * 12
    assert patient(reader.fastSyncRead) == dxl.COMM_SUCCESS
    assert [reader.getData(i, 132, 4) for i in IDS] == [2048] * 12


def test_writes_move_the_servos_in_real_time(port: dxl.PortHandler) -> None:
    ph = dxl.PacketHandler(2.0)
    assert patient(lambda: ph.write1ByteTxRx(port, 2, 64, 1)) == (dxl.COMM_SUCCESS, 0)
    assert patient(lambda: ph.write4ByteTxRx(port, 2, 116, 2100)) == (dxl.COMM_SUCCESS, 0)
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        position, result, _ = patient(lambda: ph.read4ByteTxRx(port, 2, 132))
        if position == 2100:
            break
    assert (position, result) == (2100, dxl.COMM_SUCCESS)


def test_missing_servo_and_wrong_baud_time_out(port: dxl.PortHandler) -> None:
    ph = dxl.PacketHandler(2.0)
    assert ph.ping(port, 13)[1] == dxl.COMM_RX_TIMEOUT
    assert port.setBaudRate(57600)
    assert ph.ping(port, 1)[1] == dxl.COMM_RX_TIMEOUT


def test_spy_url_dumps_the_traffic(served: tuple[EmulatedChain, str], tmp_path: Path) -> None:
    from snakebot.emulation.port import EmulatedPortHandler

    dump = tmp_path / "traffic.txt"
    handler = EmulatedPortHandler(f"spy://{served[1]}?file={dump}")
    assert handler.openPort() and handler.setBaudRate(BAUD)
    ping = patient(lambda: dxl.PacketHandler(2.0).ping(handler, 3))
    assert ping == (1060, dxl.COMM_SUCCESS, 0)
    handler.closePort()
    text = dump.read_text()
    assert "FF FF FD 00 03 03 00 01" in text.upper().replace("  ", " ")


@pytest.mark.parametrize("stop_from", ["client thread", "serving thread"])
def test_serve_forever_blocks_until_stopped(stop_from: str) -> None:
    import threading

    from snakebot.emulation.pty_server import PtyServer

    seen: list[str] = []

    def trace(direction: str, data: bytes) -> None:
        seen.append(direction)
        if direction == "tx" and stop_from == "serving thread":
            server.stop()  # as a signal handler inside serve_forever would

    server = PtyServer(make_chain_for_ids("XL430-W250", [1], BAUD), trace=trace)
    results: list[int] = []

    def client() -> None:
        handler = dxl.PortHandler(server.device_path)
        handler.openPort()
        handler.setBaudRate(BAUD)
        try:
            results.append(patient(lambda: dxl.PacketHandler(2.0).ping(handler, 1))[1])
            handler.closePort()
        except OSError:  # the server may hang up the terminal before the reply is read
            results.append(dxl.COMM_RX_FAIL)
        if stop_from == "client thread":
            server.stop()

    thread = threading.Thread(target=client)
    thread.start()
    server.serve_forever()
    thread.join(timeout=5)
    assert seen[0] == "rx" and "tx" in seen  # (a loaded machine may need the ping again)
    if stop_from == "client thread":
        assert results == [dxl.COMM_SUCCESS]
    with pytest.raises(EmulationError, match="stopped"):
        server.start()
    server.stop()
