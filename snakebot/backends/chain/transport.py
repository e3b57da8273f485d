"""SDK result codes to typed errors, with bounded retries and their counters.

Every SDK result that is not success becomes a :class:`~snakebot.errors.BusError` naming the port,
the servo IDs and the SDK's own text. Timeouts and corrupt packets are retried ``retries`` times.
A group read that still fails is split into single reads, so the error names the servos that are
really missing, and the SDK's zeros for them are never returned.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable, Sequence
from typing import TypeVar

from snakebot.backends.chain.faults import ServoStatusError, SyncReadError
from snakebot.backends.chain.links import Link
from snakebot.backends.dynamixel import sdk
from snakebot.errors import BusError

RETRYABLE = frozenset({sdk.COMM_RX_TIMEOUT, sdk.COMM_RX_CORRUPT, sdk.COMM_RX_FAIL})

T = TypeVar("T")
R = TypeVar("R")
UnicastOp = Callable[[], tuple[int, int, list[int]]]
"""One SDK call to one servo returning (result, error byte, data)."""


class Transport:
    """Runs SDK calls on one port; owns the retry policy and the counters the bus exposes."""

    def __init__(
        self,
        port: str,
        link: Link,
        retries: int,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if retries < 0:
            raise ValueError(f"retries must be >= 0, got {retries}")
        self.port = port
        self.link = link
        self.retries = retries
        self.retry_counts: Counter[int] = Counter()
        self.group_retries = 0
        self.group_fallbacks = 0
        self.alerts: set[int] = set()
        self.conditions: dict[int, int] = {}
        """Per servo ID, the condition bits of its last status packet that had any (the family's
        ``condition_bits``: the Alert bit, or Protocol 1.0's overload, overheating, input
        voltage); an ID leaves when a status packet comes without them."""
        self.last_instruction_s = 0.0
        self.vanished: BusError | None = None
        """The first OS error on the port (it vanished); later transactions fail the same way."""
        self._clock = clock

    def run(self, ids: Sequence[int], what: str, op: Callable[[], T]) -> T:
        """Run one SDK transaction: stamp ``last_instruction_s``; any OS error on the port
        (OSError, pyserial's SerialException, termios.error) becomes a BusError."""
        self.last_instruction_s = self._clock()
        try:
            return op()
        except sdk.PORT_ERRORS as exc:
            error = BusError(
                self.port,
                ids,
                f"{what}: the serial port vanished or failed ({exc}): adapter "
                "unplugged, cable pulled, or the emulator behind it stopped? Plug it back in and "
                "check the port name (ls /dev/serial/by-id/)",
            )
            self.vanished = self.vanished or error
            raise error from exc

    def fail(self, result: int, ids: Sequence[int], what: str) -> BusError:
        """The BusError for an SDK result, with the SDK's own text."""
        return BusError(self.port, ids, f"{what}: {self.link.result_text(result)}")

    def check_sent(self, result: int, ids: Sequence[int], what: str) -> None:
        """Raise BusError unless a reply-less transmission succeeded."""
        if result == sdk.COMM_PORT_BUSY:
            self.link.release()
        if result != sdk.COMM_SUCCESS:
            raise self.fail(result, ids, what)

    def retry_or_raise(self, result: int, ids: Sequence[int], what: str) -> None:
        """For a failed group transaction: return to try again, or raise if retrying cannot help.

        COMM_PORT_BUSY can only be the SDK's stuck busy flag here, so it is cleared and retried;
        COMM_NOT_AVAILABLE (no group support) goes on to the single reads.
        """
        if result == sdk.COMM_PORT_BUSY:
            self.link.release()
        elif result not in RETRYABLE and result != sdk.COMM_NOT_AVAILABLE:
            raise self.fail(result, ids, what)

    def unicast(
        self,
        servo_id: int,
        what: str,
        op: UnicastOp,
        *,
        eeprom: bool = False,
        accept_alert: bool = False,
    ) -> list[int]:
        """Run ``op`` with retries; the data, or ServoStatusError / BusError naming the servo."""
        result, error = sdk.COMM_TX_FAIL, 0
        family = self.link.family
        for n in range(self.retries + 1):
            result, error, data = self.run([servo_id], what, op)
            if result == sdk.COMM_SUCCESS:
                self.note_condition(servo_id, error, accept_alert=accept_alert)
                number = family.instruction_error(error)
                if number == 0:
                    return data
                if number != family.resend_error or n == self.retries:
                    text = self.link.error_text(number)
                    if eeprom and number == family.access_error:
                        text += " (EEPROM registers can only be written with torque off)"
                    raise ServoStatusError(self.port, servo_id, error, f"{what}: {text}")
            elif result == sdk.COMM_PORT_BUSY:
                self.link.release()
            elif result not in RETRYABLE:
                break
            if n < self.retries:
                self.retry_counts[servo_id] += 1
        attempts = self.retries + 1
        raise BusError(
            self.port,
            [servo_id],
            f"{what}: {self.link.result_text(result)} "
            f"(after {attempts} attempt{'s' if attempts > 1 else ''})",
        )

    def note_condition(self, servo_id: int, error: int, *, accept_alert: bool = False) -> None:
        """Record the condition bits of a status packet from ``servo_id`` (see ``conditions``)."""
        bits = error & self.link.family.condition_bits
        if bits and not accept_alert:
            self.alerts.add(servo_id)
            self.conditions[servo_id] = bits
        elif not bits:
            self.alerts.discard(servo_id)
            self.conditions.pop(servo_id, None)

    def group_read(
        self,
        ids: Sequence[int],
        attempt: Callable[[], R | None],
        single: Callable[[int], dict[str, int]],
        what: str,
        assemble: Callable[[dict[int, dict[str, int]]], R],
        *,
        attempts: int | None = None,
    ) -> R:
        """Run ``attempt`` (None = retryable failure) ``attempts`` times (1 + retries), then singly.

        The single reads show which servos are missing (SyncReadError) or, if all answer, serve
        the data instead, passed through ``assemble`` (``group_fallbacks`` counts that).
        """
        tries = self.retries + 1 if attempts is None else attempts
        for n in range(tries):
            result = self.run(ids, what, attempt)
            if result is not None:
                return result
            if n < tries - 1:
                self.group_retries += 1
        partial = self.single_reads(ids, single, what)
        self.group_fallbacks += 1
        return assemble(partial)

    def single_reads(
        self, ids: Sequence[int], single: Callable[[int], dict[str, int]], what: str
    ) -> dict[int, dict[str, int]]:
        """``single(id)`` for every ID (each with its own retries): ``{id: values}``, or
        SyncReadError naming the IDs that never answered (``partial`` holds the others)."""
        partial, missing = {}, []
        for servo_id in ids:
            try:
                partial[servo_id] = single(servo_id)
            except ServoStatusError:
                raise
            except BusError:
                missing.append(servo_id)
        if missing:
            raise SyncReadError(
                self.port,
                missing,
                f"{what}: no status packet from servo(s) "
                f"{', '.join(map(str, missing))} after {self.retries + 1} attempts; check their "
                "power and cable, and that their ID and baud rate match the config",
                partial,
            )
        return partial
