"""`EmulatedPortHandler`: the SDK's PortHandler, opened through `serial.serial_for_url`.

Use it with `dxlemu://<name>` for an in-process emulated chain, or with any pyserial URL, e.g.
`spy:///dev/ttyUSB0?file=dump.txt` for a traffic dump of a real bus. With `dxlemu://` the SDK's
timeouts run on the chain's clock, so a missing reply costs no real 34 ms.
"""

from __future__ import annotations

from typing import Any

import serial
from dynamixel_sdk import PortHandler

from snakebot.emulation.registry import install_url_handler

_SdkPortHandler: Any = object  # an SDK's PortHandler comes after the mixin in the MRO


class UrlPortHandler(_SdkPortHandler):  # type: ignore[misc]
    """What both vendors' emulated port handlers add to their SDK's PortHandler (mixed in before
    it): the port name is a pyserial URL, any positive baud rate is accepted, and timeouts use the
    port's `clock_ms()` when it has one."""

    is_open: bool
    ser: Any

    def __init__(self, port_name: str) -> None:
        install_url_handler()
        super().__init__(port_name)

    def setupPort(self, cflag_baud: int) -> bool:  # noqa: N802 - the SDK's name
        """Open `port_name` with `serial_for_url`, non-blocking, as the SDK expects."""
        if self.is_open:
            self.closePort()
        self.ser = serial.serial_for_url(
            self.port_name, baudrate=self.baudrate, bytesize=serial.EIGHTBITS, timeout=0
        )
        self.is_open = True
        self.ser.reset_input_buffer()
        self.tx_time_per_byte = (1000.0 / self.baudrate) * 10.0
        return True

    def getCFlagBaud(self, baudrate: int) -> int:  # noqa: N802 - the SDK's name
        """Accept every positive rate; the port (or the emulator) decides what it supports."""
        return baudrate if baudrate > 0 else -1

    def getCurrentTime(self) -> float:  # noqa: N802 - the SDK's name
        """Milliseconds on the port's clock (the emulated bus clock for `dxlemu://`)."""
        clock = getattr(self.ser, "clock_ms", None)
        if callable(clock) and self.is_open:
            return float(clock())
        return float(super().getCurrentTime())


class EmulatedPortHandler(UrlPortHandler, PortHandler):  # type: ignore[misc]
    """A `dynamixel_sdk.PortHandler` whose port name is a pyserial URL.

    Any positive baud rate is accepted (the stock handler rejects 4.5 Mbps, which X-series and
    the emulator support). Timeouts use the port's `clock_ms()` when it has one.
    """
