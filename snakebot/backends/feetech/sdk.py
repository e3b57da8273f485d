"""The one module that imports ``scservo_sdk`` (Feetech's official SDK, ftservo-python-sdk 2.0.1):
a link with the chain's link surface, so the Dynamixel chain's bus, read plans, stopping and
supervision drive Feetech servos unchanged.

The SDK's camelCase stays in this file. :class:`FeetechLink` answers every call with the chain's
result codes (``snakebot.backends.dynamixel.sdk.COMM_*``: the SDK's own numbers differ), so the
transport's retry rules read the same on both vendors. The packet handler is the SDK's
``protocol_packet_handler`` with the family's ``protocol_end`` (0 STS, little-endian words;
1 SCS, big-endian), as its ``sms_sts`` and ``scscl`` classes build it.
"""

from __future__ import annotations

import os
import select
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any, Protocol

import numpy as np
import scservo_sdk as _ft

from snakebot.backends.dynamixel import sdk as chain
from snakebot.config.ports import url_scheme
from snakebot.errors import BusError
from snakebot.families import ServoFamily

RESULTS: dict[int, int] = {
    _ft.COMM_SUCCESS: chain.COMM_SUCCESS,
    _ft.COMM_PORT_BUSY: chain.COMM_PORT_BUSY,
    _ft.COMM_TX_FAIL: chain.COMM_TX_FAIL,
    _ft.COMM_RX_FAIL: chain.COMM_RX_FAIL,
    _ft.COMM_TX_ERROR: chain.COMM_TX_ERROR,
    _ft.COMM_RX_WAITING: chain.COMM_RX_WAITING,
    _ft.COMM_RX_TIMEOUT: chain.COMM_RX_TIMEOUT,
    _ft.COMM_RX_CORRUPT: chain.COMM_RX_CORRUPT,
    _ft.COMM_NOT_AVAILABLE: chain.COMM_NOT_AVAILABLE,
}
"""scservo_sdk result code -> the chain's (Dynamixel SDK) code of the same meaning."""
_BACK = {mine: theirs for theirs, mine in RESULTS.items()}

INST_RECOVERY = 0x06  # parameter recovery: everything but the ID (ft-scs.md §4)
INST_RESTART = 0x08  # restart: no status packet (ft-scs.md §4)

LINE_RATES = (1_000_000, 500_000, 250_000, 128_000, 115_200, 76_800, 57_600, 38_400)
"""The rates Feetech's baud index names (memory-sts.md); the SDK's own list lacks 76 800."""


def _result(code: int) -> int:
    return RESULTS.get(code, chain.COMM_TX_FAIL)


class ScsPortHandlerLike(Protocol):
    """What the link uses of ``scservo_sdk.PortHandler`` (or the emulator's subclass)."""

    is_using: bool
    is_open: bool

    def closePort(self) -> None:  # noqa: N802
        """Close the serial port."""

    def setBaudRate(self, baudrate: int) -> bool:  # noqa: N802
        """Reopen at ``baudrate``; False for a rate the handler refuses."""

    def getPortName(self) -> str:  # noqa: N802
        """The device path or URL."""


PortHandlerFactory = Callable[[str], ScsPortHandlerLike]


class WaitingScsPortHandler(_ft.PortHandler):  # type: ignore[misc]
    """The SDK's ``PortHandler`` whose reads wait on the port instead of spinning, and that opens
    every rate of Feetech's baud table (the stock list has no 76 800).

    As :class:`snakebot.backends.dynamixel.sdk.WaitingPortHandler`: an empty read waits up to
    ``WAIT_S`` in ``select`` for the next byte, and a pseudo-terminal (``snakebot emulate
    --pty``) gets ``PTY_SLACK_MS`` on each reply wait, so a busy emulator is not taken for a
    missing servo. A real adapter keeps the SDK's timeouts (about 50 ms).
    """

    WAIT_S = 0.001
    PTY_SLACK_MS = 100.0
    ser: Any
    packet_timeout: float

    def __init__(self, port_name: str) -> None:
        super().__init__(port_name)
        self.slack_ms = self.PTY_SLACK_MS if chain.is_pseudo_terminal(port_name) else 0.0

    def getCFlagBaud(self, baudrate: int) -> int:  # noqa: N802 - the SDK's name
        """Feetech's line rates and the SDK's own list; -1 otherwise."""
        known = super().getCFlagBaud(baudrate)
        return baudrate if baudrate in LINE_RATES else int(known)

    def setPacketTimeout(self, packet_length: int) -> None:  # noqa: N802 - the SDK's name
        """The SDK's reply timeout for ``packet_length`` bytes, plus the pty slack."""
        super().setPacketTimeout(packet_length)
        self.packet_timeout += self.slack_ms

    def readPort(self, length: int) -> bytes:  # noqa: N802 - the SDK's name
        """Up to ``length`` bytes; waits up to ``WAIT_S`` for the first one when none is there."""
        data: bytes = self.ser.read(length)
        if data or os.name != "posix":
            return data
        try:
            select.select([self.ser.fileno()], [], [], self.WAIT_S)
        except (OSError, ValueError, AttributeError):
            return data
        more: bytes = self.ser.read(length)
        return more


_URL_PORT_HANDLERS: dict[str, PortHandlerFactory] = {}


def register_url_port_handler(scheme: str, factory: PortHandlerFactory) -> None:
    """Open ``scheme://...`` Feetech ports with ``factory`` from now on (idempotent); the
    emulator registers its ``dxlemu`` handler here as it does for the Dynamixel SDK."""
    _URL_PORT_HANDLERS[scheme.lower()] = factory


def port_handler_for(port: str) -> ScsPortHandlerLike:
    """The port handler for ``port``: a registered URL scheme's, else the SDK's for a device
    path (waiting reads); BusError for a URL whose scheme nothing in this process serves."""
    scheme = url_scheme(port)
    if scheme is None:
        handler: ScsPortHandlerLike = WaitingScsPortHandler(port)
        return handler
    factory = _URL_PORT_HANDLERS.get(scheme)
    if factory is None:
        raise BusError(
            port,
            (),
            f"nothing in this program serves {scheme}:// ports: an emulator URL names "
            "a chain started in the same process (from another process, run `snakebot emulate "
            "--pty` and use the device path it prints)",
        )
    return factory(port)


class FeetechLink:
    """One opened port plus the SDK's packet handler for the family's byte order, with the
    method surface of :class:`snakebot.backends.dynamixel.sdk.SdkLink`; every call returns the
    chain's result codes."""

    def __init__(self, port: ScsPortHandlerLike, family: ServoFamily) -> None:
        self.port = port
        self.family = family
        self.packet: Any = _ft.protocol_packet_handler(port, int(family.sdk_protocol))

    @contextmanager
    def guard(self) -> Iterator[None]:
        """Clear the SDK's busy flag if an exception escapes a transaction (as SdkLink)."""
        try:
            yield
        except BaseException:
            self.port.is_using = False
            raise

    def release(self) -> None:
        """Force the busy flag off."""
        self.port.is_using = False

    def open(self, baud: int) -> bool:
        """Open the port at ``baud``; False if the handler rejects the rate."""
        with self.guard():
            return bool(self.port.setBaudRate(baud))

    def close(self) -> None:
        """Close the port (idempotent; a port that vanished is closed as far as it can be)."""
        self.port.is_using = False
        if self.port.is_open:
            try:
                self.port.closePort()
            except chain.PORT_ERRORS:
                self.port.is_open = False

    @property
    def port_name(self) -> str:
        """The name the port was opened with."""
        return str(self.port.getPortName())

    def result_text(self, result: int) -> str:
        """The SDK's text for a (chain) result code."""
        return str(self.packet.getTxRxResult(_BACK.get(result, result)))

    def error_text(self, error: int) -> str:
        """The SDK's text for a status byte, or the family's names of its bits."""
        text = str(self.packet.getRxPacketError(error))
        return text or ", ".join(self.family.status_errors(error))

    def ping(self, servo_id: int) -> tuple[int, int, int]:
        """(model number, result, error byte): PING, then the SDK reads the model number
        (address 3, two bytes in the family's byte order)."""
        with self.guard():
            model, result, error = self.packet.ping(servo_id)
        return int(model), _result(result), int(error)

    def broadcast_ping(self) -> tuple[dict[int, list[int]], int]:
        """Feetech has no broadcast ping scan: ({}, COMM_NOT_AVAILABLE)."""
        return {}, chain.COMM_NOT_AVAILABLE

    def reboot(self, servo_id: int) -> tuple[int, int]:
        """Restart (0x08): sent, never answered (the servo boots again, ~1.8 s)."""
        with self.guard():
            packet = [0, 0, servo_id, 2, INST_RESTART, 0]
            result = self.packet.txPacket(packet)
            self.port.is_using = False
        return _result(result), 0

    def factory_reset(self, servo_id: int, option: int) -> tuple[int, int]:
        """Parameter recovery (0x06): everything but the ID (``option`` is not sent)."""
        with self.guard():
            packet = [0, 0, servo_id, 2, INST_RECOVERY, 0]
            _, result, error = self.packet.txRxPacket(packet)
        return _result(result), int(error)

    def read(self, servo_id: int, address: int, length: int) -> tuple[list[int], int, int]:
        """(data bytes, result, error byte)."""
        with self.guard():
            data, result, error = self.packet.readTxRx(servo_id, address, length)
        return data, _result(result), int(error)

    def read_unguarded(
        self, servo_id: int, address: int, length: int
    ) -> tuple[list[int], int, int]:
        """:meth:`read` for a loop that guards itself (one READ per servo every cycle)."""
        data, result, error = self.packet.readTxRx(servo_id, address, length)
        return data, RESULTS.get(result, chain.COMM_TX_FAIL), error

    def write(self, servo_id: int, address: int, data: bytes) -> tuple[int, int]:
        """(result, error byte); broadcast writes get no reply."""
        with self.guard():
            result, error = self.packet.writeTxRx(servo_id, address, len(data), list(data))
        return _result(result), int(error)

    def sync_write(self, address: int, length: int, param: list[int] | bytes) -> int:
        """Send prepared SYNC_WRITE parameters ``[id, data...]*N``; the result code."""
        try:  # guard() spelled out: this runs every control cycle
            result = self.packet.syncWriteTxOnly(address, length, param, len(param))
        except BaseException:
            self.port.is_using = False
            raise
        return RESULTS.get(result, chain.COMM_TX_FAIL)

    def sync_writer(
        self, address: int, size: int, rows: Sequence[tuple[int, bytes]]
    ) -> FeetechSyncWriter:
        """A SYNC_WRITE of one block to ``rows`` (``(id, block bytes)``)."""
        return FeetechSyncWriter(self, address, size, rows)

    def sync_reader(self, address: int, size: int, ids: Sequence[int]) -> FeetechSyncReader:
        """A reusable SYNC_READ (0x82) of one block from ``ids`` (the read plan asks for one
        only where the capabilities have it: not on SCS)."""
        return FeetechSyncReader(self, address, size, ids)

    def bulk_reader(self, blocks: Sequence[tuple[int, int, int]]) -> Any:
        """Feetech has no Bulk Read: ValueError."""
        raise ValueError(f"{self.family.name} has no bulk read")


def link(handler: ScsPortHandlerLike, family: ServoFamily) -> FeetechLink:
    """The Feetech link over ``handler`` (``snakebot.backends.chain.links.link_for``)."""
    return FeetechLink(handler, family)


class FeetechSyncWriter:
    """A ``GroupSyncWrite`` of one contiguous block, its rows checked before ``addParam``."""

    def __init__(
        self, link: FeetechLink, address: int, size: int, rows: Sequence[tuple[int, bytes]]
    ) -> None:
        group = _ft.GroupSyncWrite(link.packet, address, size)
        for servo_id, data in rows:
            if len(data) != size:
                raise ValueError(f"servo {servo_id}: {len(data)} data bytes, register needs {size}")
            if not group.addParam(servo_id, list(data)):
                raise ValueError(f"servo {servo_id} appears twice in one sync write")
        self._link = link
        self._group = group

    def send(self) -> int:
        """Transmit the SYNC_WRITE (no status reply); the chain's result code."""
        with self._link.guard():
            return _result(self._group.txPacket())


class FeetechSyncReader:
    """A ``GroupSyncRead`` (SYNC_READ 0x82) of one block from fixed IDs, built once and reused.

    The SDK sends the request and waits for every reply (or its timeout). Its ``rxPacket`` then
    searches the whole reply for each servo's status packet in turn, byte by byte (most of a
    cycle's host CPU with 12 servos); here the reply is checked in one numpy pass where it is
    what a healthy chain sends, every servo's packet in request order, each with its header,
    ID, length and checksum checked as the SDK's ``readRx`` does. Anything else (a servo
    missing, a reply out of order, a bad checksum) goes to the SDK's own search, so one missing
    servo does not lose the others' data. ``data_dict`` holds the error byte first, then the
    block, either way.
    """

    def __init__(self, link: FeetechLink, address: int, size: int, ids: Sequence[int]) -> None:
        group = _ft.GroupSyncRead(link.packet, address, size)
        for servo_id in ids:
            if not group.addParam(servo_id):
                raise ValueError(f"servo {servo_id} appears twice in one sync read")
        self._link = link
        self._group = group
        self.address = address
        self.size = size
        self.ids = tuple(ids)
        # The status packet each servo sends, in request order: FF FF id length (size + 2).
        self._heads = np.array([(0xFF, 0xFF, i, size + 2) for i in self.ids], dtype=np.uint8)
        self._reply_size = (size + 6) * len(self.ids)
        self._joined: bytes | None = None

    def transact(self, fast: bool) -> int:
        """Run one SYNC_READ (``fast`` is ignored: Feetech has no Fast Sync Read)."""
        # No stale data survives: every ID's entry is set (None for a servo not found), or the
        # result is a failure.
        group, self._joined = self._group, None
        try:  # guard() spelled out: this runs every control cycle
            result = group.txPacket()
            if result != _ft.COMM_SUCCESS:
                return _result(result)
            result, reply = group.ph.syncReadRx(self.size, len(self.ids))
            if not self._take_whole(reply):
                result = self._search(reply, result)
        except BaseException:
            self._link.release()
            raise
        return RESULTS.get(result, chain.COMM_TX_FAIL)

    def _take_whole(self, reply: list[int]) -> bool:
        """Keep a reply that is every servo's status packet in request order, all intact."""
        if len(reply) != self._reply_size:
            return False
        packets = np.array(reply, dtype=np.uint8).reshape(len(self.ids), self.size + 6)
        # Checksum: ~(ID + length + error + data) & 0xFF, so adding it back gives 0xFF.
        sums = packets[:, 2:].sum(axis=1, dtype=np.uint32)
        if not (np.array_equal(packets[:, :4], self._heads) and (sums & 0xFF == 0xFF).all()):
            return False
        rows = packets[:, 4:-1]
        self._joined = rows.tobytes()
        self._group.data_dict.update(zip(self.ids, rows.tolist(), strict=True))
        self._group.last_result = True
        return True

    def _search(self, reply: list[int], result: int) -> int:
        """The SDK's ``rxPacket`` on a reply already read: each ID's packet found by its
        ``readRx``; the result is the SDK's (the last ID's search, or the read's own)."""
        group = self._group
        group.last_result = len(reply) >= self.size + 6
        if not group.last_result:
            return result
        for servo_id in group.data_dict:
            group.data_dict[servo_id], result = group.readRx(reply, servo_id, self.size)
            group.last_result &= result == _ft.COMM_SUCCESS
        return result

    def available(self, servo_id: int) -> bool:
        """Whether the last read holds this servo's block."""
        ok, _ = self._group.isAvailable(servo_id, self.address, self.size)
        return bool(ok)

    def error(self, servo_id: int) -> int:
        """The status byte of this servo's reply in the last read."""
        data = self._group.data_dict.get(servo_id) or [0]
        return int(data[0])

    prefix = 1
    """Bytes in front of each servo's block in :meth:`joined`: its status byte."""

    def joined(self) -> bytes | bytearray | None:
        """Every servo's row of the last read in ID order, its status byte first, or None when
        one is missing (the SDK's entry empty or None)."""
        if self._joined is not None:
            return self._joined
        buffer = bytearray()
        entries, want = self._group.data_dict, self.size + 1
        for servo_id in self.ids:
            row = entries.get(servo_id)
            if not row or len(row) != want:
                return None
            buffer.extend(row)
        return buffer

    def data(self, servo_id: int) -> list[int]:
        """This servo's block bytes from the last read; check :meth:`available` first."""
        data: list[int] = self._group.data_dict[servo_id][1:]
        return data
