"""A scripted serial port at the OS edge: the real SDK packet code runs, replies come from a script.

Each instruction the SDK writes pops one entry of ``script``: bytes to answer with, or None for
silence (the SDK then times out at once instead of after 34 ms). Packets come from the emulator's
codec, which is written independently of the SDK.
"""

from __future__ import annotations

from collections.abc import Callable

from snakebot.emulation.protocol import build_fast_status, build_status
from snakebot.emulation.protocol1 import build_status as build_status1


def status(servo_id: int, error: int = 0, params: bytes = b"") -> bytes:
    """One Protocol 2.0 status packet."""
    return build_status(servo_id, error, params)


def fast_status(entries: list[tuple[int, bytes]]) -> bytes:
    """One Fast Sync Read reply (ID 0xFE, unstuffed) carrying ``(id, data)`` segments."""
    return build_fast_status([(servo_id, 0, data) for servo_id, data in entries])


def corrupt(packet: bytes) -> bytes:
    """The packet with its CRC broken."""
    return packet[:-1] + bytes([packet[-1] ^ 0xFF])


Reply = bytes | None | Callable[[bytes], bytes | None]


class ScriptedPort:
    """Enough of ``dynamixel_sdk.PortHandler`` for the SDK's packet handler; no SDK import."""

    def __init__(self, port_name: str = "fake0") -> None:
        self.port_name = port_name
        self.is_open = False
        self.is_using = False
        self.baudrate = 1_000_000
        self.script: list[Reply] = []
        self.written: list[bytes] = []
        self.fail_on_read: BaseException | None = None
        self._rx = b""
        self._exhausted = False

    # what ServoBus uses
    def closePort(self) -> None:  # noqa: N802
        self.is_open = False

    def setBaudRate(self, baudrate: int) -> bool:  # noqa: N802
        self.baudrate = baudrate
        self.is_open = True
        return True

    def getPortName(self) -> str:  # noqa: N802
        return self.port_name

    # what the SDK's packet handler uses
    def getBaudRate(self) -> int:  # noqa: N802
        return self.baudrate

    def clearPort(self) -> None:  # noqa: N802
        self._rx = b""

    def writePort(self, packet: list[int]) -> int:  # noqa: N802
        data = bytes(packet)
        self.written.append(data)
        reply = self.script.pop(0) if self.script else None
        if callable(reply):
            reply = reply(data)
        self._rx = reply or b""
        self._exhausted = False
        return len(data)

    def readPort(self, length: int) -> bytes:  # noqa: N802
        if self.fail_on_read is not None:
            raise self.fail_on_read
        chunk, self._rx = self._rx[:length], self._rx[length:]
        if len(chunk) < length:
            self._exhausted = True
        return chunk

    def setPacketTimeout(self, packet_length: int) -> None:  # noqa: N802
        self._exhausted = False

    def setPacketTimeoutMillis(self, msec: float) -> None:  # noqa: N802
        self._exhausted = False

    def isPacketTimeout(self) -> bool:  # noqa: N802
        return self._exhausted and not self._rx


def status1(servo_id: int, error: int = 0, params: bytes = b"") -> bytes:
    """One Protocol 1.0 status packet (the emulator's own codec)."""
    return build_status1(servo_id, error, params)
