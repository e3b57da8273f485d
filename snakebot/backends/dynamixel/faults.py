"""Errors and warnings of the Dynamixel backend, and the decoding of Hardware Error Status bits."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

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
"""Status-packet error byte bit 7: the servo has latched a hardware error (read register 70)."""


def decode_hardware_error(value: int) -> tuple[str, ...]:
    """Names of the bits set in a Hardware Error Status value, low bit first."""
    names = [name for bit, name in HARDWARE_ERROR_BITS.items() if value >> bit & 1]
    unknown = [bit for bit in range(8) if value >> bit & 1 and bit not in HARDWARE_ERROR_BITS]
    return tuple(names) + tuple(f"bit{bit}" for bit in unknown)


def reboot_command(port: str, servo_id: int) -> str:
    """The CLI line that clears a latched hardware error."""
    return f"snakebot servo reboot --port {port} --id {servo_id}"


class HardwareFaultError(ServoFaultError):
    """Latched hardware errors on one or more servos; ``faults`` maps ID to the register value.

    ``servo_id``/``flags`` describe the lowest faulty ID; the message names the others and the
    reboot command that clears the latch.
    """

    def __init__(self, port: str, faults: Mapping[int, int]) -> None:
        self.port = port
        self.faults = dict(faults)
        servo_id = min(self.faults)
        others = [
            f"servo {i} ({', '.join(decode_hardware_error(v))})"
            for i, v in sorted(self.faults.items())
            if i != servo_id
        ]
        message = (
            "Its torque is off until it is rebooted: remove the cause (stalled or overloaded "
            f"joint, supply voltage, heat), then run `{reboot_command(port, servo_id)}` or "
            "power-cycle it"
        )
        if others:
            message += f". Also faulty: {'; '.join(others)}"
        super().__init__(servo_id, decode_hardware_error(self.faults[servo_id]), message)


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
        super().__init__(port, sorted({*missing, *mismatched}), message)


class ServoSettingsError(BackendError):
    """EEPROM settings on the servos contradict the robot config; the backend refuses to run."""

    def __init__(self, port: str, problems: Sequence[str]) -> None:
        self.port = port
        self.problems = tuple(problems)
        lines = "\n  - ".join(self.problems)
        super().__init__(
            f"{port}: servo settings do not match the robot config:\n  - {lines}\n"
            "Write them with `snakebot config apply` (torque off) or Dynamixel Wizard 2.0."
        )


class DynamixelSettingsWarning(UserWarning):
    """A servo or adapter setting that works but costs loop rate (latency timer, return delay)."""
