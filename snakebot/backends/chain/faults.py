"""Errors and warnings of the Dynamixel backend, and the decoding of Hardware Error Status bits."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from snakebot.errors import BackendError, BusError, ServoFaultError

# Hardware Error Status (70) / Shutdown (63) bits of the X series (e-Manual control_table_shutdown,
# reference/dynamixel.md §2.4); bits 1, 6 and 7 are unused.
HARDWARE_ERROR_BITS: Mapping[int, str] = {
    0: "input_voltage",
    2: "overheating",
    3: "motor_encoder",
    4: "electrical_shock",
    5: "overload",
}

ALERT_BIT = 0x80
"""Protocol 2.0 status error byte bit 7: the servo has latched a hardware error (read 70)."""


def decode_hardware_error(value: int) -> tuple[str, ...]:
    """Names of the bits set in a Hardware Error Status value, low bit first."""
    names = [name for bit, name in HARDWARE_ERROR_BITS.items() if value >> bit & 1]
    unknown = [bit for bit in range(8) if value >> bit & 1 and bit not in HARDWARE_ERROR_BITS]
    return tuple(names) + tuple(f"bit{bit}" for bit in unknown)


def reboot_command(port: str, servo_id: int) -> str:
    """The CLI line that clears a latched hardware error."""
    return f"snakebot servo reboot --port {port} --id {servo_id}"


class HardwareFaultError(ServoFaultError):
    """Latched hardware errors on one or more servos; ``faults`` maps ID to the fault bits.

    The bits are Hardware Error Status (X series; named by :func:`decode_hardware_error`) or,
    for a model without that register, the status packet's condition bits (``decode``: the
    family's ``status_errors``). ``servo_id``/``flags`` describe the lowest faulty ID; the
    message names the others and ``remedy`` (default: the reboot command that clears the latch).
    """

    def __init__(
        self,
        port: str,
        faults: Mapping[int, int],
        *,
        decode: Callable[[int], tuple[str, ...]] = decode_hardware_error,
        remedy: str | None = None,
    ) -> None:
        self.port = port
        self.faults = dict(faults)
        servo_id = min(self.faults)
        others = [
            f"servo {i} ({', '.join(decode(v))})"
            for i, v in sorted(self.faults.items())
            if i != servo_id
        ]
        message = remedy or (
            "Its torque is off until it is rebooted: remove the cause (stalled or overloaded "
            f"joint, supply voltage, heat), then run `{reboot_command(port, servo_id)}` or "
            "power-cycle it"
        )
        if others:
            message += f". Also faulty: {'; '.join(others)}"
        super().__init__(servo_id, decode(self.faults[servo_id]), message)


class ServoStatusError(BusError):
    """A servo answered with an error number in its status packet (range, access, length...)."""

    def __init__(self, port: str, servo_id: int, error_byte: int, message: str) -> None:
        self.error_byte = error_byte
        super().__init__(port, [servo_id], message)


class SyncReadError(BusError):
    """A group read failed after its retries; ``missing_ids`` never answered, even alone.

    ``partial`` holds what the servos that did answer returned, read one at a time; the SDK's
    zeros for the missing ones are never published.
    """

    def __init__(
        self,
        port: str,
        missing_ids: Sequence[int],
        message: str,
        partial: Mapping[int, Mapping[str, int]] | None = None,
    ) -> None:
        self.missing_ids = tuple(missing_ids)
        self.partial = dict(partial or {})
        super().__init__(port, missing_ids, message)


class ChainMismatchError(BusError):
    """The servos on the bus are not the configured chain (missing IDs, wrong models, extras)."""

    def __init__(
        self,
        port: str,
        *,
        missing: Sequence[int],
        unexpected: Sequence[int],
        mismatched: Mapping[int, tuple[int, int]],
        message: str,
    ) -> None:
        self.missing = tuple(missing)
        self.unexpected = tuple(unexpected)
        self.mismatched = dict(mismatched)
        super().__init__(port, sorted({*missing, *mismatched}) or self.unexpected, message)


class ServoSettingsError(BackendError):
    """EEPROM settings on the servos contradict the robot config; the backend refuses to run."""

    def __init__(self, port: str, problems: Sequence[str]) -> None:
        self.port = port
        self.problems = tuple(problems)
        lines = "\n  - ".join(self.problems)
        super().__init__(
            f"{port}: servo settings do not match the robot config:\n  - {lines}\n"
            "Write them with `snakebot config apply` (torque off), Dynamixel Wizard 2.0 or "
            "Feetech's FD tool."
        )


class PoseOutsideLimitsError(BackendError):
    """A joint stands where its servo cannot hold it (beyond the EEPROM Min/Max Position Limit).

    Torque on would jump it to the limit; the backend refuses instead. Angles in rad.
    """

    def __init__(
        self, port: str, joint: int, servo_id: int, angle_rad: float, limit_rad: float
    ) -> None:
        self.port = port
        self.joint = joint
        self.servo_id = servo_id
        self.angle_rad = angle_rad
        self.limit_rad = limit_rad
        super().__init__(
            f"{port}: joint {joint} (servo {servo_id}) measures {angle_rad:.3f} rad, beyond its "
            f"servo's position limit at {limit_rad:.3f} rad (EEPROM Min/Max Position Limit), "
            "where it cannot hold: torque "
            "on would jump it to the limit. Move the joint inside by hand (its torque is off), or "
            "widen the limit with `snakebot config apply`"
        )


class TrackingError(BackendError):
    """Joints stopped following their goals and the backend could not bring them back.

    ``joints`` are joint indices (head = 0), ``servo_ids`` their servos; ``present_rad`` and
    ``goal_rad`` where each stands and where it was told to go.
    """

    def __init__(
        self,
        port: str,
        joints: Sequence[int],
        servo_ids: Sequence[int],
        present_rad: Sequence[float],
        goal_rad: Sequence[float],
        reason: str,
    ) -> None:
        self.port = port
        self.joints = tuple(joints)
        self.servo_ids = tuple(servo_ids)
        self.present_rad = tuple(present_rad)
        self.goal_rad = tuple(goal_rad)
        where = "; ".join(
            f"joint {j} (servo {i}) at {p:.3f} rad, goal {g:.3f} rad"
            for j, i, p, g in zip(joints, servo_ids, present_rad, goal_rad, strict=True)
        )
        super().__init__(
            f"{port}: position feedback stopped following the goals: {where}. {reason}"
        )


class WatchdogTripError(BackendError):
    """The Bus Watchdog tripped more often than the backend recovers from: the host cannot feed it.

    ``trips`` is how many trips came within ``window_s`` seconds.
    """

    def __init__(
        self, port: str, servo_ids: Sequence[int], trips: int, window_s: float, watchdog_s: float
    ) -> None:
        self.port = port
        self.servo_ids = tuple(servo_ids)
        self.trips = trips
        super().__init__(
            f"{port}: the Bus Watchdog ({watchdog_s * 1000:.0f} ms) of servo(s) "
            f"{', '.join(map(str, servo_ids))} tripped {trips} times within {window_s:.0f} s: the "
            "servos stop whenever no instruction reaches them within the watchdog period. The "
            "host is too loaded or the USB link stalls; close other programs, lower the control "
            "rate, or raise watchdog_s"
        )


class StopIncompleteError(BackendError):
    """After the stop ramp some servos that answer do not hold the safe pose (hold policy)."""

    def __init__(self, port: str, servo_ids: Sequence[int], detail: str) -> None:
        self.port = port
        self.servo_ids = tuple(servo_ids)
        super().__init__(
            f"{port}: servo(s) {', '.join(map(str, servo_ids))} did not take the "
            f"safe pose at stop: {detail}"
        )


class ServoSettingsWarning(UserWarning):
    """A servo or adapter setting that works but costs loop rate (latency timer, return delay)."""


class ExtraServosWarning(UserWarning):
    """Servos on the bus that the robot file does not name, accepted with ``allow_extra_servos``."""
