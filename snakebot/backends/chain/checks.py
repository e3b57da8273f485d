"""Connect-time checks: is the bus the configured chain, do EEPROM settings fit, what caps the rate.

Policy: settings that make the backend wrong or unsafe are errors (:class:`ServoSettingsError`):
Operating Mode other than 3 (position) or, where the model has it, 5 (current-based position:
position control under Goal Current, what a torque limit uses), the Drive Mode reverse bit
(direction lives in the config), Min/Max Position Limits that do not cover a joint's configured
range (on AX/MX: CW/CCW Angle Limit, both 0 = wheel mode), and, on a model without a Bus Watchdog,
an Alarm Shutdown that does not turn torque off on overload and overheating (all that protects it
when the host dies). Settings that only cost loop rate are warnings (:class:`ServoSettingsWarning`):
Return Delay Time above 0, a USB latency timer above 1 ms, and the Drive Mode profile/torque-on-goal
bits. Registers a model does not have (AX: no Operating or Drive Mode) are not checked.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from snakebot.backends.chain.faults import ChainMismatchError
from snakebot.backends.chain.ticks import TickConverter
from snakebot.families import ServoFamily
from snakebot.servo_tables import ServoTable

SETTINGS_KEYS = ("return_delay_time", "drive_mode", "operating_mode")
"""The settings every X-series servo is checked for (:func:`settings_keys` per model)."""
LIMIT_KEYS = ("max_position_limit", "min_position_limit")
POSITION_MODE = 3
CURRENT_POSITION_MODE = 5
"""Dynamixel current-based position control: follows Goal Position with the current bounded by
Goal Current (e-Manual, Operating Mode). It ignores Min/Max Position Limit (multi-turn)."""
SHUTDOWN_NEEDED = 0x24
"""Alarm Shutdown bits 2 (overheating) and 5 (overload): torque off when either happens."""
SYSFS_USB_SERIAL = Path("/sys/bus/usb-serial/devices")

SHUTDOWN_DEFAULT_NAME = "Alarm Shutdown"
"""What the docs call the register that turns torque off on a fault where the datasheet name is
the bare "Shutdown" (X series 63, AX/MX 18)."""

_DRIVE_REVERSE = 0x01
_DRIVE_TIME_PROFILE = 0x04
_DRIVE_TORQUE_ON_GOAL = 0x08


@dataclass(frozen=True)
class ChainReport:
    """Who answered: ``found`` maps ID to model number; what is wrong with the chain, if anything.

    ``unexpected`` maps IDs that are on the bus but not in the config to their model number;
    ``mismatched`` maps ID to (found model number, expected model number).
    """

    found: Mapping[int, int]
    missing: tuple[int, ...]
    unexpected: Mapping[int, int] = field(default_factory=dict)
    mismatched: Mapping[int, tuple[int, int]] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True when every configured servo answered with the expected model."""
        return not (self.missing or self.mismatched)


def chain_report(
    ids: Sequence[int],
    model_number: int,
    found: Mapping[int, int],
    on_bus: Mapping[int, int] | None = None,
) -> ChainReport:
    """Compare pinged ``found`` ({id: model}) and, if scanned, ``on_bus`` with the config."""
    missing = tuple(i for i in ids if i not in found)
    mismatched = {i: (m, model_number) for i, m in found.items() if m != model_number}
    unexpected = {i: m for i, m in sorted((on_bus or {}).items()) if i not in ids}
    return ChainReport(dict(found), missing, unexpected, mismatched)


EXTRA_SERVOS_HINT = (
    "the robot file does not name them: is this the right robot file? If they are meant to be on "
    "the bus, allow extra servos (backend option allow_extra_servos); a new servo "
    "is ID 1 at 57600 bit/s: give it its configured ID"
)


def chain_error(
    port: str,
    baud: int,
    report: ChainReport,
    model_names: Mapping[int, str],
    extra_hint: str = EXTRA_SERVOS_HINT,
) -> ChainMismatchError:
    """The connect failure for a report that is not ok (or has extras); every line says what to
    check. ``extra_hint`` follows the list of unexpected IDs."""

    def name(number: int) -> str:
        return model_names.get(number, f"model {number}")

    lines = []
    if report.missing:
        lines.append(
            f"missing servo ID(s) {', '.join(map(str, report.missing))}: no answer to "
            f"ping at {baud} bit/s (check power, cables, ID and baud rate)"
        )
    for servo_id, (got, want) in sorted(report.mismatched.items()):
        lines.append(f"servo {servo_id} is a {name(got)}, the config expects a {name(want)}")
    if report.unexpected:
        extra = ", ".join(f"{i} ({name(m)})" for i, m in report.unexpected.items())
        lines.append(f"unexpected servo ID(s) on the bus: {extra} ({extra_hint})")
    return ChainMismatchError(
        port,
        missing=report.missing,
        unexpected=tuple(report.unexpected),
        mismatched=report.mismatched,
        message="; ".join(lines),
    )


def has_current_position(table: ServoTable) -> bool:
    """Whether the model has current-based position control (Operating Mode 5 with Goal
    Current and Current Limit registers: XM430, XM540, XH430, XL330, MX-64/106 2.0)."""
    return (
        CURRENT_POSITION_MODE in table.specs.operating_modes
        and "goal_current" in table
        and "current_limit" in table
    )


def current_position_mode(table: ServoTable) -> int | None:
    """The model's Operating Mode of current-based position control (5), None where it has
    none: what ``check_settings`` accepts beside position control."""
    return CURRENT_POSITION_MODE if has_current_position(table) else None


def settings_keys(table: ServoTable) -> tuple[str, ...]:
    """The registers of :data:`SETTINGS_KEYS` that model ``table`` has."""
    return tuple(key for key in SETTINGS_KEYS if key in table)


def shutdown_name(table: ServoTable) -> str:
    """The datasheet name of the register that turns torque off on a fault (``shutdown``):
    Feetech's "Unload Condition", Dynamixel's "Alarm Shutdown" (its tables say "Shutdown")."""
    if "shutdown" not in table or table["shutdown"].name == "Shutdown":
        return SHUTDOWN_DEFAULT_NAME
    return table["shutdown"].name


def check_settings(
    settings: Mapping[int, Mapping[str, int]],
    ids: Sequence[int],
    converter: TickConverter,
    *,
    watchdog: bool = True,
    position_mode: int = POSITION_MODE,
    current_position_mode: int | None = None,
    shutdown_register: str = SHUTDOWN_DEFAULT_NAME,
) -> tuple[list[str], list[str]]:
    """(errors, warnings) for EEPROM ``settings`` ({id: {key: value}}) against the joints.

    ``ids`` are head to tail, in the converter's joint order. Keys a model has no register for
    are left out of ``settings`` and not checked; ``watchdog=False`` (no Bus Watchdog) makes an
    Alarm Shutdown (``shutdown``; Feetech's Unload Condition, the same bits) without the
    overload and overheating bits an error, the register named ``shutdown_register``
    (:func:`shutdown_name` of the model). ``position_mode`` is the Operating Mode of
    position control on the model (``table.specs.position_mode``: 3 Dynamixel, 0 Feetech STS);
    ``current_position_mode`` (5 where the model has current-based position control) is
    accepted too.
    """
    errors: list[str] = []
    warnings: list[str] = []
    slow = sorted(i for i in ids if settings[i]["return_delay_time"] > 0)
    for joint, servo_id in enumerate(ids):
        values = settings[servo_id]
        mode, drive = values.get("operating_mode", position_mode), values.get("drive_mode", 0)
        if mode != position_mode and mode != current_position_mode:
            also = (
                ""
                if current_position_mode is None
                else f" or {current_position_mode} (current-based position control)"
            )
            errors.append(
                f"servo {servo_id}: Operating Mode is {mode}, needs {position_mode} "
                f"(position control){also}"
            )
        shutdown = values.get("shutdown")
        if not watchdog and shutdown is not None and shutdown & SHUTDOWN_NEEDED != SHUTDOWN_NEEDED:
            errors.append(
                f"servo {servo_id}: {shutdown_register} is {shutdown}, needs bits 2 and 5 "
                f"(overheating, overload; {SHUTDOWN_NEEDED} or more): with no Bus "
                "Watchdog it is what turns torque off on a servo held against an "
                "obstacle after the host died"
            )
        if drive & _DRIVE_REVERSE:
            errors.append(
                f"servo {servo_id}: Drive Mode has the reverse bit set; snakebot takes "
                "the direction from the config (joints[].direction), clear the bit"
            )
        if drive & (_DRIVE_TIME_PROFILE | _DRIVE_TORQUE_ON_GOAL):
            warnings.append(
                f"servo {servo_id}: Drive Mode {drive} sets the time-based-profile "
                "or torque-on-by-goal bit; snakebot expects 0"
            )
        low, high = values["min_position_limit"], values["max_position_limit"]
        want_low, want_high = converter.lower_ticks[joint], converter.upper_ticks[joint]
        if low == high == 0 and "operating_mode" not in values:
            errors.append(
                f"servo {servo_id}: CW and CCW Angle Limit are both 0, which is wheel "
                f"mode; joint {joint} needs position control over "
                f"{want_low}..{want_high} ticks"
            )
        elif low > want_low or high < want_high:
            errors.append(
                f"servo {servo_id}: Min/Max Position Limit {low}..{high} ticks do not cover "
                f"joint {joint}'s range {converter.lower_rad[joint]:.3f}.."
                f"{converter.upper_rad[joint]:.3f} rad ({want_low}..{want_high} ticks)"
            )
    current_based = [i for i in ids if settings[i].get("operating_mode") == current_position_mode]
    if current_based and current_position_mode is not None:
        warnings.append(
            f"servo(s) {', '.join(map(str, current_based))} in Operating Mode "
            f"{current_position_mode} (current-based position control) ignore their Min/Max "
            "Position Limit: only snakebot's joint limits (lower_rad/upper_rad) bound the goals"
        )
    if slow:
        delay_us = max(2 * settings[i]["return_delay_time"] for i in slow)
        warnings.append(
            f"Return Delay Time up to {delay_us} µs on servo(s) {', '.join(map(str, slow))}: "
            "every reply waits that long (per servo in a Sync or Bulk Read or one Read per servo, "
            "once in a Fast Sync Read); set it to 0 with `snakebot config apply`"
        )
    return errors, warnings


def usb_latency_timer_ms(port: str, sysfs_root: Path = SYSFS_USB_SERIAL) -> int | None:
    """The FTDI latency timer of a Linux USB-serial port in ms, or None where there is none."""
    if "://" in port:
        return None
    try:
        device = Path(port).resolve().name
        text = (sysfs_root / device / "latency_timer").read_text(encoding="ascii")
        return int(text.strip())
    except (OSError, ValueError):
        return None


def latency_warning(
    port: str, latency_ms: int, wire_time_s: float, turnarounds: int = 1
) -> str | None:
    """A warning with the fix when the latency timer caps the loop rate (above 1 ms).

    ``turnarounds`` is how many replies the cycle waits for one at a time (one per servo with
    a Read per servo): each may wait a whole latency timer.
    """
    if latency_ms <= 1:
        return None
    cap_hz = 1.0 / (turnarounds * latency_ms * 1e-3 + wire_time_s)
    device = Path(port).resolve().name
    return (
        f"{port}: USB latency timer is {latency_ms} ms, which caps the control loop near "
        f"{cap_hz:.0f} Hz. Fix: echo 1 | sudo tee /sys/bus/usb-serial/devices/{device}/"
        'latency_timer (persist with the udev rule ATTR{device/latency_timer}="1")'
    )


def cycle_wire_time_s(
    family: ServoFamily,
    method: str,
    servo_count: int,
    read_bytes: int,
    baud: int,
    *,
    write_bytes: int = 4,
) -> tuple[float, int]:
    """(bus seconds, reply turnarounds) of one control cycle at Return Delay Time 0: one Sync
    Write of ``write_bytes`` per servo (goal position) plus one read of ``read_bytes`` per servo
    by ``method``, at 10 bits per byte (``family.read_cost``, ``sync_write_bytes``)."""
    cost = family.read_cost(method, servo_count, read_bytes)
    total = cost.wire_bytes + family.sync_write_bytes(servo_count, write_bytes)
    return total * 10.0 / baud, cost.return_delays
