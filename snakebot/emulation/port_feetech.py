"""`EmulatedScsPortHandler`: Feetech's `scservo_sdk.PortHandler`, opened through
`serial.serial_for_url`.

The same `dxlemu://<name>` URLs as `port.EmulatedPortHandler` (one scheme: the chain decides what
answers, Dynamixel or Feetech servos), or any pyserial URL. With `dxlemu://` the SDK's timeouts
run on the chain's clock, so a missing reply costs no real 50 ms. The stock handler opens
`serial.Serial(port=...)`, which takes no URL.
"""

from __future__ import annotations

from scservo_sdk import PortHandler

from snakebot.emulation.port import UrlPortHandler


class EmulatedScsPortHandler(UrlPortHandler, PortHandler):  # type: ignore[misc]
    """A `scservo_sdk.PortHandler` whose port name is a pyserial URL.

    Any positive baud rate is accepted (the stock handler's list is the SDK's, not the port's).
    Timeouts use the port's `clock_ms()` when it has one.
    """
