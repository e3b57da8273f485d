"""The highest control rate a Dynamixel bus can hold, from the bus's own arithmetic.

One cycle is one Sync Write of goals plus one state read by the family's read method. It costs

- the wire: ``family.read_cost`` + ``family.sync_write_bytes`` at the baud, 10 bits a
  byte (8N1);
- the Return Delay Time of every reply turnaround the read has (one per servo for a Sync Read,
  a Bulk Read or a Read per servo; one for a Fast Sync Read);
- a USB latency tail for every time the host waits for a reply before it sends again: once for a
  group read, once per servo for a Read per servo. An FTDI adapter (U2D2, USB2Dynamixel) hands
  what it received to the host when its latency timer runs out: 1 ms at latency_timer 1, which is
  assumed unless the port's real timer can be read (Linux sysfs); a pseudo-terminal or an emulator
  URL has none.

Servo processing time is left out (tens of µs per reply on MX-64/106): the result is a ceiling,
and :func:`check_rate` refuses only rates above it.
"""

from __future__ import annotations

from dataclasses import dataclass

from snakebot.backends.chain.checks import usb_latency_timer_ms
from snakebot.backends.dynamixel.sdk import is_pseudo_terminal
from snakebot.config.schema import RobotConfig
from snakebot.config.servos.settings import joint_settings
from snakebot.errors import ConfigError
from snakebot.families import ServoFamily
from snakebot.servo_tables import ServoTable

ASSUMED_USB_TAIL_S = 0.001
"""The wait an FTDI adapter adds to each reply at latency_timer 1 (its smallest setting)."""

METHOD_NAMES = {
    "fast_sync_read": "one Fast Sync Read",
    "sync_read": "one Sync Read",
    "bulk_read": "one Bulk Read",
    "read": "one Read per servo",
}


class RateTooHighError(ConfigError):
    """A control rate above what the servo bus can hold; ``max_rate_hz`` is the most it can.

    Raised before anything moves. ``budget`` says where a cycle's time goes.
    """

    def __init__(self, rate_hz: float, budget: CycleBudget) -> None:
        self.rate_hz = rate_hz
        self.max_rate_hz = budget.max_rate_hz
        self.budget = budget
        super().__init__(
            "rate_hz",
            f"{rate_hz:g}",
            (
                f"the servo bus cannot hold {rate_hz:g} Hz: at most {budget.max_rate_hz:.0f} Hz. "
                f"{budget.describe()}. For more: {'; '.join(budget.remedies())}"
            ),
        )


@dataclass(frozen=True)
class CycleBudget:
    """Where one control cycle's bus time goes (seconds) and the rate that leaves.

    ``turnarounds`` replies each wait ``return_delay_s``; ``round_trips`` host waits each pay
    ``usb_tail_s``.
    """

    family: ServoFamily
    method: str
    servo_count: int
    baud: int
    wire_s: float
    turnarounds: int
    return_delay_s: float
    round_trips: int
    usb_tail_s: float
    usb_assumed: bool
    fastest_baud: int = 0
    """The fastest baud rate the model and the SDK both take (0: not known)."""

    @property
    def cycle_s(self) -> float:
        """Wire time + return delays + USB tails of one cycle."""
        return (
            self.wire_s
            + self.turnarounds * self.return_delay_s
            + self.round_trips * self.usb_tail_s
        )

    @property
    def max_rate_hz(self) -> float:
        """The highest control rate the bus holds."""
        return 1.0 / self.cycle_s

    def remedies(self) -> list[str]:
        """What would make the cycle shorter here, biggest lever first where it applies."""
        out = []
        if self.fastest_baud > self.baud:
            out.append(
                f"a faster baud rate (up to {self.fastest_baud} bit/s for this model: "
                "[bus] baud, written to the servos by `snakebot config apply`)"
            )
        if self.return_delay_s > 0:
            out.append(
                "Return Delay Time 0 (return_delay_time_us = 0 in the robot's "
                "[settings], then `snakebot config apply`)"
            )
        if self.usb_tail_s > ASSUMED_USB_TAIL_S or self.usb_assumed:
            out.append(
                "the USB adapter's latency timer at 1 ms (echo 1 | sudo tee "
                "/sys/bus/usb-serial/devices/ttyUSB0/latency_timer)"
            )
        if self.round_trips > 1:
            out.append(
                "fewer servos per port (each Read waits for its own reply: split the "
                "chain over two adapters)"
            )
        return out or ["a lower rate: this bus is at its fastest settings"]

    def describe(self) -> str:
        """One sentence: what a cycle costs and why."""
        usb = f"{self.round_trips} x {self.usb_tail_s * 1e3:.0f} ms USB latency" + (
            " (assumed: an FTDI adapter at latency_timer 1)" if self.usb_assumed else ""
        )
        return (
            f"{self.servo_count} servos on {self.family.name} at {self.baud} bit/s, read by "
            f"{METHOD_NAMES[self.method]}, take {self.cycle_s * 1e3:.2f} ms a cycle: "
            f"{self.wire_s * 1e3:.2f} ms on the wire, {self.turnarounds} x "
            f"{self.return_delay_s * 1e6:.0f} µs Return Delay Time, {usb}"
        )


def cycle_budget(
    family: ServoFamily,
    method: str,
    servo_count: int,
    read_bytes: int,
    write_bytes: int,
    baud: int,
    return_delay_s: float,
    usb_tail_s: float = ASSUMED_USB_TAIL_S,
    *,
    usb_assumed: bool = True,
    fastest_baud: int = 0,
) -> CycleBudget:
    """The budget of one cycle: Sync Write of ``write_bytes`` per servo, read of ``read_bytes``
    per servo by ``method`` (one of ``snakebot.families.READ_METHODS``); ``fastest_baud`` is
    what a remedy may suggest."""
    cost = family.read_cost(method, servo_count, read_bytes)
    wire = (cost.wire_bytes + family.sync_write_bytes(servo_count, write_bytes)) * 10.0 / baud
    return CycleBudget(
        family,
        method,
        servo_count,
        baud,
        wire,
        cost.return_delays,
        return_delay_s,
        cost.round_trips,
        usb_tail_s,
        usb_assumed,
        fastest_baud,
    )


SDK_MAX_BAUD = 4_000_000
"""dynamixel_sdk's PortHandler takes rates up to 4 Mbps (4.5 Mbps needs a custom handler)."""


def fastest_baud(table: ServoTable) -> int:
    """The fastest rate model ``table`` has that the SDK opens."""
    rates = [b for b in table.baud_rates.values() if b <= SDK_MAX_BAUD]
    return max(rates, default=0)


def usb_tail_s(port: str) -> tuple[float, bool]:
    """(seconds each reply may wait in the USB adapter, whether that is assumed) for ``port``:
    the latency timer where Linux shows it, nothing for a pty or an emulator URL, else 1 ms."""
    if "://" in port or is_pseudo_terminal(port):
        return 0.0, False
    latency = usb_latency_timer_ms(port)
    if latency is not None:
        return latency * 1e-3, False
    return ASSUMED_USB_TAIL_S, True


def wanted_return_delay_s(robot: RobotConfig, table: ServoTable) -> float:
    """The longest Return Delay Time the robot's servos are set to have (seconds): the servo
    file's and robot file's ``[settings]`` and the joints' own, else the model's factory value."""
    register = table["return_delay_time"]
    raws = []
    for own in joint_settings(robot.servo.source, robot.source, robot.joint_count, table):
        setting = own.get(register.key)
        raws.append(register.default if setting is None else setting.raw)
    return max(raws, default=register.default) * register.scale


def check_rate(budget: CycleBudget, rate_hz: float) -> None:
    """RateTooHighError when ``rate_hz`` is above what ``budget`` leaves."""
    if rate_hz > budget.max_rate_hz:
        raise RateTooHighError(rate_hz, budget)
