"""The live Foxglove server against hostile clients, with real WebSocket clients on 127.0.0.1:
pages from other sites refused, a bounded number of clients, a client that never reads dropped
without slowing the writer, failed sends counted instead of printed."""

from __future__ import annotations

import base64
import json
import os
import socket
import time
from collections.abc import Iterator

import numpy as np
import pytest

pytest.importorskip("foxglove")
pytest.importorskip("websockets")

from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from snakebot.telemetry.foxglove_live import FoxgloveTelemetry, TelemetryOptions
from tests.integration.telemetry.foxglove_client import SUBPROTOCOLS, FoxgloveClient
from tests.records import record

JOINTS = 12


@pytest.fixture
def server(request: pytest.FixtureRequest) -> Iterator[FoxgloveTelemetry]:
    options = getattr(request, "param", {})
    sink = FoxgloveTelemetry(
        TelemetryOptions(port=0, **options), servo_ids=range(1, JOINTS + 1), rate_hz=100.0
    )
    try:
        yield sink
    finally:
        sink.close()


def write_cycles(sink: FoxgloveTelemetry, first: int, count: int) -> list[float]:
    """Write ``count`` cycles from ``first`` (100 Hz robot time) as fast as it goes; the wall
    seconds each write took."""
    rng = np.random.default_rng(first)
    took = []
    for cycle in range(first, first + count):
        values = rng.normal(size=(4, JOINTS))
        started = time.perf_counter()
        sink(record(cycle, cycle / 100.0, values[0], values[1], values[2], values[3]))
        took.append(time.perf_counter() - started)
    return took


def url(sink: FoxgloveTelemetry) -> str:
    return f"ws://127.0.0.1:{sink.port}"


def status_of(sink: FoxgloveTelemetry, origin: str | None) -> int:
    """101 when a client sending ``origin`` gets the upgrade, else the HTTP status it got."""
    headers = {} if origin is None else {"Origin": origin}
    try:
        with connect(
            url(sink), subprotocols=SUBPROTOCOLS, additional_headers=headers, open_timeout=20
        ) as ws:
            assert json.loads(ws.recv(timeout=20))["op"] == "serverInfo"
            return 101
    except InvalidStatus as exc:
        return int(exc.response.status_code)


def never_reading_client(sink: FoxgloveTelemetry) -> socket.socket:
    """A raw client that upgrades, subscribes to every channel and never reads again."""
    sock = socket.create_connection(("127.0.0.1", sink.port), timeout=20)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    key = base64.b64encode(os.urandom(16)).decode()
    sock.sendall(
        f"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
        f"Sec-WebSocket-Protocol: {SUBPROTOCOLS[0]}\r\n\r\n".encode()
    )
    head, _, rest = _read_until(sock, b"", b"\r\n\r\n")
    assert head.startswith(b"HTTP/1.1 101"), head
    channels: list[int] = []
    while not channels:  # serverInfo, then the advertisement
        text, rest = _server_frame(sock, rest)
        message = json.loads(text)
        if message["op"] == "advertise":
            channels = [channel["id"] for channel in message["channels"]]
    subscribe = {
        "op": "subscribe",
        "subscriptions": [
            {"id": number, "channelId": channel} for number, channel in enumerate(channels, 1)
        ],
    }
    sock.sendall(_masked_text(json.dumps(subscribe).encode()))
    return sock


def _read_until(sock: socket.socket, data: bytes, end: bytes) -> tuple[bytes, bytes, bytes]:
    while end not in data:
        chunk = sock.recv(65536)
        assert chunk, "the server closed"
        data += chunk
    return data.partition(end)


def _server_frame(sock: socket.socket, data: bytes) -> tuple[bytes, bytes]:
    """One unmasked frame's payload from ``data`` plus what ``sock`` gives; and what follows."""

    def need(count: int) -> None:
        nonlocal data
        while len(data) < count:
            chunk = sock.recv(65536)
            assert chunk, "the server closed"
            data += chunk

    need(2)
    length, start = data[1] & 0x7F, 2
    if length == 126:
        need(4)
        length, start = int.from_bytes(data[2:4], "big"), 4
    elif length == 127:
        need(10)
        length, start = int.from_bytes(data[2:10], "big"), 10
    need(start + length)
    return data[start : start + length], data[start + length :]


def _masked_text(payload: bytes) -> bytes:
    mask = os.urandom(4)
    assert len(payload) < 65536
    length = (
        bytes([0x80 | len(payload)])
        if len(payload) < 126
        else (bytes([0x80 | 126]) + len(payload).to_bytes(2, "big"))
    )
    return b"\x81" + length + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload))


def test_a_page_from_another_site_is_refused_and_local_and_foxglove_pages_are_served(
    server: FoxgloveTelemetry,
) -> None:
    assert status_of(server, "https://evil.example") == 403
    assert status_of(server, "http://127.0.0.1.evil.example") == 403
    assert status_of(server, "null") == 403  # a sandboxed frame of any site
    for origin in (
        None,
        "https://app.foxglove.dev",
        "http://localhost:8080",
        "http://127.0.0.1:3000",
        "http://[::1]",
    ):
        assert status_of(server, origin) == 101, origin
    assert server.client_counts()["refused_origin"] == 3


@pytest.mark.parametrize("server", [{"origins": ("https://viz.example.org",)}], indirect=True)
def test_an_origin_the_user_names_is_served(server: FoxgloveTelemetry) -> None:
    assert status_of(server, "https://viz.example.org") == 101
    assert status_of(server, "https://viz.example.org.evil.example") == 403


@pytest.mark.parametrize("server", [{"max_clients": 3}], indirect=True)
def test_the_client_beyond_the_limit_is_refused_until_one_leaves(
    server: FoxgloveTelemetry,
) -> None:
    clients = [FoxgloveClient(url(server)) for _ in range(3)]
    for client in clients:
        client.read_advertisements({"/joints"})
    assert status_of(server, None) == 503
    clients.pop().close()
    deadline = time.monotonic() + 20
    while status_of(server, None) != 101:  # the gate notices the close
        assert time.monotonic() < deadline
        time.sleep(0.05)
    for client in clients:
        client.close()
    counts = server.client_counts()
    assert counts["refused_full"] >= 1 and counts["accepted"] >= 4


@pytest.mark.parametrize("server", [{"stall_s": 1.0}], indirect=True)
def test_a_client_that_never_reads_is_dropped_and_the_writer_never_waits(
    server: FoxgloveTelemetry,
) -> None:
    hostile = [never_reading_client(server) for _ in range(3)]
    took: list[float] = []
    cycle = 0
    started = time.monotonic()
    while server.client_counts()["dropped_slow"] < len(hostile):
        assert time.monotonic() - started < 60, server.client_counts()
        took += write_cycles(server, cycle, 200)
        cycle += 200
        time.sleep(0.01)
    # The writer never waited for them: writes cost a small part of a 100 Hz cycle, and none
    # waited anywhere near as long as the gate waited for the clients (a loaded machine can
    # still pre-empt any one of them for a scheduler slice).
    assert float(np.mean(took)) < 0.001 and max(took) < 0.1, sorted(took)[-5:]
    assert server.clients == 0  # their places are free again
    watcher = FoxgloveClient(url(server))
    watcher.read_advertisements({"/joints"})
    watcher.subscribe(["/joints"])
    time.sleep(0.2)
    write_cycles(server, cycle, 20)
    watcher.collect({"/joints": 20})
    assert watcher.messages["/joints"][-1][1]["cycle"] == cycle + 19
    watcher.close()
    for sock in hostile:
        sock.close()


def test_failed_sends_are_counted_not_printed(
    server: FoxgloveTelemetry, capfd: pytest.CaptureFixture[str]
) -> None:
    for _ in range(5):
        sock = never_reading_client(server)
        write_cycles(server, 0, 50)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")
        sock.close()  # a reset, mid-stream
        write_cycles(server, 50, 500)
    deadline = time.monotonic() + 20
    while server.client_counts()["send_errors"] == 0:
        assert time.monotonic() < deadline, server.client_counts()
        write_cycles(server, 0, 100)
        time.sleep(0.01)
    server.close()
    assert capfd.readouterr().err == ""
