"""Errors of the servo-setup tools; each message says what was refused and what to do instead."""

from __future__ import annotations

from collections.abc import Sequence

from snakebot.errors import BusError, SnakebotError


class SetupError(SnakebotError):
    """A setup step was refused or could not finish (the message gives the reason and the fix)."""


class VerifyError(BusError):
    """A register read back a different value than was just written to it."""

    def __init__(self, port: str, servo_id: int, key: str, wrote: int, read: int) -> None:
        self.key = key
        self.wrote = wrote
        self.read = read
        super().__init__(
            port,
            [servo_id],
            f"wrote {key} = {wrote} but it reads back {read}; the servo did not "
            "take the value (torque on? out of range for this model?)",
        )


class DuplicateIdError(BusError):
    """Two or more servos answer to one ID: replies collide (corrupt packets, mixed models)."""

    def __init__(self, port: str, problems: Sequence[tuple[int, int, str]]) -> None:
        self.problems = tuple(problems)
        lines = "; ".join(f"ID {i} at {b} baud: {why}" for i, b, why in self.problems)
        super().__init__(
            port,
            sorted({i for i, _, _ in self.problems}),
            f"{lines}. Where two servos share an ID, connect them one at a time and give each "
            "its own ID with `snakebot config assign-id` (Dynamixel Wizard's ID Inspection also "
            "works)",
        )
