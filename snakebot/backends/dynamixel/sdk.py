"""The one backend module that imports ``dynamixel_sdk``: Protocols for its classes, thin adapters.

The SDK's camelCase stays in this file. Everything else in the package talks to :class:`SdkLink`,
:class:`SyncWriter`, :class:`SyncReader` and :class:`BulkReader`, whose methods are snake_case,
typed, and never leave the port's busy flag stuck (see :meth:`SdkLink.guard`).
"""

from __future__ import annotations

import inspect
import os
import select
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any, Protocol

import dynamixel_sdk as _sdk

from snakebot.config.ports import url_scheme
from snakebot.errors import BusError
from snakebot.families import ServoFamily

try:
    import termios
except ImportError:  # Windows: pyserial reports everything as OSError (SerialException)
    PORT_ERRORS: tuple[type[Exception], ...] = (OSError,)
else:
    # pyserial lets termios.error (not an OSError) out of reset_input_buffer's tcflush when the
    # device vanished under it (a USB adapter unplugged, a pty whose far end closed).
    PORT_ERRORS = (OSError, termios.error)

COMM_SUCCESS: int = _sdk.COMM_SUCCESS
COMM_PORT_BUSY: int = _sdk.COMM_PORT_BUSY
COMM_TX_FAIL: int = _sdk.COMM_TX_FAIL
COMM_RX_FAIL: int = _sdk.COMM_RX_FAIL
COMM_TX_ERROR: int = _sdk.COMM_TX_ERROR
COMM_RX_WAITING: int = _sdk.COMM_RX_WAITING
COMM_RX_TIMEOUT: int = _sdk.COMM_RX_TIMEOUT
COMM_RX_CORRUPT: int = _sdk.COMM_RX_CORRUPT
COMM_NOT_AVAILABLE: int = _sdk.COMM_NOT_AVAILABLE
BROADCAST_ID: int = _sdk.BROADCAST_ID
MAX_ID: int = _sdk.MAX_ID


class PortHandlerLike(Protocol):
    """What we use of ``dynamixel_sdk.PortHandler`` (or a subclass such as the emulator's)."""

    is_using: bool
    is_open: bool

    def closePort(self) -> None:  # noqa: N802
        """Close the serial port."""

    def setBaudRate(self, baudrate: int) -> bool:  # noqa: N802
        """Reopen at ``baudrate``; False for rates the SDK does not know."""

    def getPortName(self) -> str:  # noqa: N802
        """The device path or URL."""


PortHandlerFactory = Callable[[str], PortHandlerLike]
"""Builds a port handler from a port name; ``dynamixel_sdk.PortHandler`` by default."""


class PacketHandlerLike(Protocol):
    """What we use of ``Protocol2PacketHandler`` / ``Protocol1PacketHandler``."""

    def getTxRxResult(self, result: int) -> str:  # noqa: N802
        """Text for a COMM_* result code."""

    def getRxPacketError(self, error: int) -> str:  # noqa: N802
        """Text for a status error byte."""

    def ping(self, port: PortHandlerLike, dxl_id: int) -> tuple[int, int, int]:
        """(model number, result, error byte)."""

    def broadcastPing(self, port: PortHandlerLike) -> tuple[dict[int, list[int]], int]:  # noqa: N802
        """({id: [model number, firmware]}, result)."""

    def reboot(self, port: PortHandlerLike, dxl_id: int) -> tuple[int, int]:
        """(result, error byte)."""

    def factoryReset(  # noqa: N802
        self, port: PortHandlerLike, dxl_id: int, option: int
    ) -> tuple[int, int]:
        """(result, error byte)."""

    def readTxRx(  # noqa: N802
        self, port: PortHandlerLike, dxl_id: int, address: int, length: int
    ) -> tuple[list[int], int, int]:
        """(data bytes, result, error byte)."""

    def writeTxRx(  # noqa: N802
        self, port: PortHandlerLike, dxl_id: int, address: int, length: int, data: list[int]
    ) -> tuple[int, int]:
        """(result, error byte)."""

    def bulkReadTx(  # noqa: N802
        self, port: PortHandlerLike, param: list[int], param_length: int
    ) -> int:
        """Send a Bulk Read request (Protocol 1.0's signature; 2.0's adds ``fast_option``)."""

    def syncWriteTxOnly(  # noqa: N802
        self,
        port: PortHandlerLike,
        start_address: int,
        data_length: int,
        param: list[int] | bytes,
        param_length: int,
    ) -> int:
        """Result of sending prepared ``[id, data...]*N`` parameters."""


class GroupSyncWriteLike(Protocol):
    """``dynamixel_sdk.GroupSyncWrite``."""

    def addParam(self, dxl_id: int, data: list[int]) -> bool:  # noqa: N802
        """False if the ID is already in the group (or data too long)."""

    def txPacket(self) -> int:  # noqa: N802
        """Send the group instruction; result."""


class GroupSyncReadLike(Protocol):
    """``dynamixel_sdk.GroupSyncRead``; ``data_dict`` holds each ID's raw bytes after a read."""

    data_dict: dict[int, list[int] | bytearray]

    def addParam(self, dxl_id: int) -> bool:  # noqa: N802
        """False if the ID is already in the group (or data too long)."""

    def txRxPacket(self) -> int:  # noqa: N802
        """Send and collect every status; result."""

    def fastSyncRead(self) -> int:  # noqa: N802
        """Fast Sync Read (one combined status packet); result."""

    def isAvailable(self, dxl_id: int, address: int, data_length: int) -> bool:  # noqa: N802
        """Whether the last read holds data for that ID and range."""


class GroupBulkReadLike(Protocol):
    """``dynamixel_sdk.GroupBulkRead``; ``data_dict`` holds ``[data, address, length]`` per ID."""

    data_dict: dict[int, list[Any]]
    param: list[int]
    last_result: bool

    def makeParam(self) -> None:  # noqa: N802
        """Build ``param`` from the added IDs and blocks."""

    def rxPacket(self) -> int:  # noqa: N802
        """Collect every status of a Bulk Read already sent; result."""

    def addParam(self, dxl_id: int, start_address: int, data_length: int) -> bool:  # noqa: N802
        """False if the ID is already in the group (or data too long)."""

    def txRxPacket(self) -> int:  # noqa: N802
        """Send and collect every status; result."""

    def isAvailable(self, dxl_id: int, address: int, data_length: int) -> bool:  # noqa: N802
        """Whether the last read holds data for that ID and range."""


def is_pseudo_terminal(port: str) -> bool:
    """Whether ``port`` is a pseudo-terminal (Linux /dev/pts/N, macOS /dev/ttysNNN)."""
    path = os.path.realpath(port)
    return path.startswith("/dev/pts/") or path.startswith("/dev/ttys")


class WaitingPortHandler(_sdk.PortHandler):  # type: ignore[misc]
    """The SDK's ``PortHandler`` whose reads, when nothing has arrived, wait on the port.

    The SDK's receive loop polls a non-blocking read until its timeout, spinning a core at 100 %
    for every reply. Here an empty read waits up to ``WAIT_S`` in ``select`` for the next byte and
    returns as soon as one arrives, so the loop sleeps in the kernel instead: replies come no
    later, timeouts at most ``WAIT_S`` later, and on a loaded machine the CPU goes to whoever is
    producing the reply (an emulator on the same host, the USB stack). POSIX only; elsewhere the
    SDK's own polling stays.

    On a pseudo-terminal the far end is a process (``snakebot emulate --pty``, a socat bridge),
    which the OS may not schedule for tens of milliseconds on a loaded host: each reply wait gets
    ``PTY_SLACK_MS`` more than the SDK's (about 34 ms), so a busy emulator is not taken for a
    missing servo. A real adapter keeps the SDK's timeouts.
    """

    WAIT_S = 0.001
    PTY_SLACK_MS = 100.0
    ser: Any
    packet_timeout: float

    def __init__(self, port_name: str) -> None:
        super().__init__(port_name)
        self.slack_ms = self.PTY_SLACK_MS if is_pseudo_terminal(port_name) else 0.0

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
            return data  # a port that cannot be waited on: poll as the SDK does
        more: bytes = self.ser.read(length)
        return more


def default_port_handler(port: str) -> PortHandlerLike:
    """The SDK's ``PortHandler`` for a device path (plain ``serial.Serial``: no URLs), with
    reads that wait on the port instead of spinning (:class:`WaitingPortHandler`)."""
    handler: PortHandlerLike = WaitingPortHandler(port)
    return handler


_URL_PORT_HANDLERS: dict[str, PortHandlerFactory] = {}


def register_url_port_handler(scheme: str, factory: PortHandlerFactory) -> None:
    """Open ``scheme://...`` ports with ``factory`` from now on (idempotent).

    The emulator registers its ``dxlemu`` handler when it registers a chain, so production code
    opens emulator URLs without importing the emulator. snakebot.config.ports still decides which
    schemes may be opened at all.
    """
    _URL_PORT_HANDLERS[scheme.lower()] = factory


def port_handler_for(port: str) -> PortHandlerLike:
    """The port handler for ``port``: a registered URL scheme's, else the SDK's for a device path.

    Raises BusError for a URL whose scheme nothing in this process registered (an emulator URL
    addresses a chain inside the same program).
    """
    scheme = url_scheme(port)
    if scheme is None:
        return default_port_handler(port)
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


class SdkLink:
    """One opened port plus the packet handler of its servo family (``family.sdk_protocol``:
    the SDK's Protocol 2.0 or 1.0 handler); every call returns the SDK's raw result codes."""

    def __init__(self, port: PortHandlerLike, family: ServoFamily) -> None:
        self.port = port
        self.family = family
        self.packet: PacketHandlerLike = _sdk.PacketHandler(family.sdk_protocol)

    @contextmanager
    def guard(self) -> Iterator[None]:
        """Clear the SDK's non-reentrant busy flag if an exception escapes a transaction.

        ``port.is_using`` is set in ``txPacket`` and cleared at the end of ``rxPacket``; anything
        raised in between (a serial error, Ctrl-C, the IndexError of a short ``addParam``) would
        otherwise leave every later call answering "Port is in use!".
        """
        try:
            yield
        except BaseException:
            self.port.is_using = False
            raise

    def release(self) -> None:
        """Force the busy flag off (after a COMM_PORT_BUSY nobody else can be causing)."""
        self.port.is_using = False

    def open(self, baud: int) -> bool:
        """Open the port at ``baud``; False if the SDK rejects the rate."""
        with self.guard():
            # setBaudRate (re)opens the port at that rate; openPort would open at 1 Mbps first.
            return bool(self.port.setBaudRate(baud))

    def close(self) -> None:
        """Close the port (idempotent; a port that vanished is closed as far as it can be)."""
        self.port.is_using = False
        if self.port.is_open:
            try:
                self.port.closePort()
            except PORT_ERRORS:
                self.port.is_open = False

    @property
    def port_name(self) -> str:
        """The name the port was opened with."""
        return str(self.port.getPortName())

    def result_text(self, result: int) -> str:
        """The SDK's text for a COMM_* result code."""
        return str(self.packet.getTxRxResult(result))

    def error_text(self, error: int) -> str:
        """The SDK's text for a status packet's error byte."""
        return str(self.packet.getRxPacketError(error))

    def ping(self, dxl_id: int) -> tuple[int, int, int]:
        """(model number, result, error byte)."""
        with self.guard():
            return self.packet.ping(self.port, dxl_id)

    def broadcast_ping(self) -> tuple[dict[int, list[int]], int]:
        """({id: [model number, firmware]}, result)."""
        with self.guard():
            return self.packet.broadcastPing(self.port)

    def reboot(self, dxl_id: int) -> tuple[int, int]:
        """(result, error byte)."""
        with self.guard():
            return self.packet.reboot(self.port, dxl_id)

    def factory_reset(self, dxl_id: int, option: int) -> tuple[int, int]:
        """(result, error byte); a family without reset options resets everything."""
        with self.guard():
            if not self.family.factory_reset_takes_option:
                result, error = self.packet.factoryReset(self.port, dxl_id)  # type: ignore[call-arg]
                return int(result), int(error)
            return self.packet.factoryReset(self.port, dxl_id, option)

    def read(self, dxl_id: int, address: int, length: int) -> tuple[list[int], int, int]:
        """(data bytes, result, error byte)."""
        with self.guard():
            return self.packet.readTxRx(self.port, dxl_id, address, length)

    def read_unguarded(self, dxl_id: int, address: int, length: int) -> tuple[list[int], int, int]:
        """:meth:`read` without :meth:`guard`, for a loop that guards itself (one Read per servo
        every control cycle)."""
        return self.packet.readTxRx(self.port, dxl_id, address, length)

    def write(self, dxl_id: int, address: int, data: bytes) -> tuple[int, int]:
        """(result, error byte); broadcast writes get no reply."""
        with self.guard():
            return self.packet.writeTxRx(self.port, dxl_id, address, len(data), list(data))

    def sync_write(self, address: int, length: int, param: list[int] | bytes) -> int:
        """Send prepared Sync Write parameters ``[id, data...]*N`` (list or bytes); result code."""
        try:  # guard() spelled out: this runs every control cycle
            return self.packet.syncWriteTxOnly(self.port, address, length, param, len(param))
        except BaseException:
            self.port.is_using = False
            raise

    def sync_writer(self, address: int, size: int, rows: Sequence[tuple[int, bytes]]) -> SyncWriter:
        """A Sync Write of one block to ``rows`` (``(id, block bytes)``)."""
        return SyncWriter(self, address, size, rows)

    def sync_reader(self, address: int, size: int, ids: Sequence[int]) -> SyncReader:
        """A reusable Sync Read of one block from ``ids``."""
        return SyncReader(self, address, size, ids)

    def bulk_reader(self, blocks: Sequence[tuple[int, int, int]]) -> BulkReader:
        """A reusable Bulk Read of one ``(id, address, size)`` block per servo."""
        return BulkReader(self, blocks)


def link(handler: PortHandlerLike, family: ServoFamily) -> SdkLink:
    """The Dynamixel link over ``handler`` (``snakebot.backends.chain.links.link_for``)."""
    return SdkLink(handler, family)


class SyncWriter:
    """A ``GroupSyncWrite`` of one contiguous block, its rows checked before ``addParam``."""

    def __init__(self, link: SdkLink, address: int, size: int, rows: Sequence[tuple[int, bytes]]):
        group: GroupSyncWriteLike = _sdk.GroupSyncWrite(link.port, link.packet, address, size)
        for dxl_id, data in rows:
            # A short row is accepted by addParam and crashes txPacket later (reference §1.7).
            if len(data) != size:
                raise ValueError(f"servo {dxl_id}: {len(data)} data bytes, register needs {size}")
            if not group.addParam(dxl_id, list(data)):
                raise ValueError(f"servo {dxl_id} appears twice in one sync write")
        self._link = link
        self._group = group

    def send(self) -> int:
        """Transmit the Sync Write (no status reply); the COMM_* result."""
        with self._link.guard():
            return self._group.txPacket()


class SyncReader:
    """A ``GroupSyncRead`` of one contiguous block from fixed IDs, built once and reused."""

    def __init__(self, link: SdkLink, address: int, size: int, ids: Sequence[int]) -> None:
        group: GroupSyncReadLike = _sdk.GroupSyncRead(link.port, link.packet, address, size)
        for dxl_id in ids:
            if not group.addParam(dxl_id):
                raise ValueError(f"servo {dxl_id} appears twice in one sync read")
        self._link = link
        self._group = group
        self.address = address
        self.size = size
        self.ids = tuple(ids)

    def transact(self, fast: bool) -> int:
        """Run one Sync Read (or Fast Sync Read); the COMM_* result."""
        try:  # guard() spelled out: this runs every control cycle
            return self._group.fastSyncRead() if fast else self._group.txRxPacket()
        except IndexError:
            # fastSyncReadRxPacket indexes past a valid but short combined reply (one servo's
            # segment missing) instead of reporting it.
            self._link.release()
            return COMM_RX_CORRUPT
        except BaseException:
            self._link.release()
            raise

    def available(self, dxl_id: int) -> bool:
        """Whether the last read holds fresh data for ``dxl_id`` (the SDK zeroes it otherwise)."""
        return bool(self._group.isAvailable(dxl_id, self.address, self.size))

    def data(self, dxl_id: int) -> list[int] | bytearray:
        """Raw block bytes of ``dxl_id`` from the last read; check :meth:`available` first."""
        return self._group.data_dict[dxl_id]

    prefix = 0
    """Bytes in front of each servo's block in :meth:`joined` (none: the SDK keeps the data)."""

    def joined(self) -> bytearray | None:
        """Every servo's block of the last read in ID order, or None when one is not there
        (``isAvailable`` per ID: after a failed read the SDK hands out zeros)."""
        buffer = bytearray()
        group = self._group
        for dxl_id in self.ids:
            if not group.isAvailable(dxl_id, self.address, self.size):
                return None
            buffer.extend(group.data_dict[dxl_id])
        return buffer


class BulkReader:
    """A ``GroupBulkRead``: one (address, size) block per ID, built once and reused.

    dynamixel_sdk 4.1's ``GroupBulkRead.txPacket`` passes Protocol 2.0's ``fast_option`` to
    every packet handler's ``bulkReadTx``, which Protocol 1.0's does not take (TypeError on
    every P1 Bulk Read). Where the handler lacks that parameter, the request goes out here
    through the handler's own ``bulkReadTx`` with the group's parameters, and the group
    collects the replies as usual.
    """

    def __init__(self, link: SdkLink, blocks: Sequence[tuple[int, int, int]]) -> None:
        group: GroupBulkReadLike = _sdk.GroupBulkRead(link.port, link.packet)
        for dxl_id, address, size in blocks:
            if not group.addParam(dxl_id, address, size):
                raise ValueError(f"servo {dxl_id} appears twice in one bulk read")
        self._link = link
        self._group = group
        self.blocks = tuple(blocks)
        parameters = inspect.signature(link.packet.bulkReadTx).parameters
        self._own_request = "fast_option" not in parameters

    def transact(self) -> int:
        """Run one Bulk Read; the COMM_* result."""
        with self._link.guard():
            if not self._own_request:
                return self._group.txRxPacket()
            group = self._group
            group.makeParam()
            result = self._link.packet.bulkReadTx(self._link.port, group.param, len(group.param))
            if result != COMM_SUCCESS:
                return result
            return group.rxPacket()

    def available(self, dxl_id: int, address: int, size: int) -> bool:
        """Whether the last read holds fresh data for that block."""
        return bool(self._group.isAvailable(dxl_id, address, size))

    def joined(self) -> bytearray | None:
        """Every block of the last read, in the order they were added, or None unless the
        whole read succeeded (``isAvailable``'s test: the SDK keeps stale data otherwise)."""
        group = self._group
        if not group.last_result:
            return None
        out = bytearray()
        entries = group.data_dict
        for dxl_id, _, size in self.blocks:
            data = entries[dxl_id][0]
            if len(data) != size:
                return None
            out += bytes(data)
        return out

    def data(self, dxl_id: int) -> list[int] | bytearray:
        """Raw block bytes of ``dxl_id`` from the last read (``data_dict`` holds
        ``[data, address, length]`` per ID)."""
        data: list[int] | bytearray = self._group.data_dict[dxl_id][0]
        return data
