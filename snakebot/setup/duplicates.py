"""What the replies to one ID show: one servo, two servos sharing the ID, or a noisy line.

Two servos with one ID answer the same instruction at nearly the same time; a UART receiving both
sees garbage (a CRC error) unless the replies are bit-for-bit equal, so every reply to that ID is
corrupt. Pings of identical models can be equal, so Present Position (which differs between
shafts) is read as well, and the model number in the ping is compared with the Model Number
register (mixed models sharing an ID). Line noise corrupts replies now and then, to any ID: an ID
that answers cleanly even once is one servo on a noisy line, not two servos.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from snakebot.backends.dynamixel import sdk
from snakebot.errors import SnakebotError
from snakebot.servo_tables import Register, table_for_model
from snakebot.setup.link import Link

TRIES = 4
"""Attempts per question before an ID counts as always corrupt: at 10 % line noise, four corrupt
replies in a row happen once in 10,000."""

CORRUPT = (sdk.COMM_RX_CORRUPT, sdk.COMM_RX_FAIL)


@dataclass(frozen=True)
class Tally:
    """Replies to one question: clean, corrupt (CRC or framing errors) and missing."""

    clean: int = 0
    corrupt: int = 0
    silent: int = 0

    @property
    def replies(self) -> int:
        """Replies that came back at all (clean or corrupt)."""
        return self.clean + self.corrupt


@dataclass(frozen=True)
class Evidence:
    """Everything learnt from asking one ID at one baud rate.

    ``pings``, ``reads`` (of Present Position) and ``info`` (reads of the table's first bytes)
    stop at the first clean reply; ``models`` are the model numbers of clean ping replies;
    ``model_register`` and ``firmware`` come from ``info`` (None if it never came back clean).
    """

    servo_id: int
    baud: int
    pings: Tally
    reads: Tally
    info: Tally
    models: tuple[int, ...]
    model_register: int | None
    firmware: int | None

    @property
    def answered(self) -> bool:
        """Whether anything at all came back (clean or corrupt)."""
        return self.pings.replies > 0

    @property
    def clean(self) -> bool:
        """Whether at least one ping came back clean."""
        return bool(self.models)

    @property
    def corrupt(self) -> int:
        """Corrupt replies among all the questions asked."""
        return self.pings.corrupt + self.reads.corrupt + self.info.corrupt

    @property
    def replies(self) -> int:
        """Replies among all the questions asked (clean or corrupt)."""
        return self.pings.replies + self.reads.replies + self.info.replies


class Kind(Enum):
    """What the replies to one ID say."""

    ABSENT = "absent"
    ONE_SERVO = "one servo"
    SHARED = "shared ID"
    GARBLED = "always corrupt"


@dataclass(frozen=True)
class Verdict:
    """``kind`` and, unless one clean servo, ``reason``: what was seen, in words."""

    kind: Kind
    reason: str = ""


def gather(link: Link, servo_id: int, baud: int, *, patient: bool = False) -> Evidence:
    """Ping ``servo_id`` at ``baud``, then read Present Position and the model and firmware
    (Model Number at 0, Firmware Version where the model's table, or else the protocol's native
    tables, keep it: 2 on an AX or MX, 6 on the X series).

    Each question is asked up to :data:`TRIES` times, until one clean reply. Unless ``patient``,
    an ID whose first two pings get no reply at all is taken as absent (two timeouts, about 70 ms
    on a real port; one alone can be a hiccup of a busy host).
    """
    models: list[int] = []
    clean = corrupt = silent = 0
    for attempt in range(TRIES):
        probe = link.probe(servo_id, baud, tries=1)
        corrupt += probe.corrupt
        silent += probe.silent
        if probe.models:
            models.extend(probe.models)
            clean += 1
            break
        if silent == attempt + 1 >= 2 and not patient:
            break
    pings = Tally(clean, corrupt, silent)
    if not models:
        return Evidence(servo_id, baud, pings, Tally(), Tally(), (), None, None)
    position, model_at, firmware_at = _layout(link, models[0])
    reads = Tally()
    if position is not None:
        reads = _ask(link, servo_id, position.address, position.size)[0]
    info, data = _ask(link, servo_id, 0, max(firmware_at, (model_at or 0) + 1) + 1, tries=2)
    model_register = firmware = None
    if data is not None:
        firmware = data[firmware_at]
        if model_at is not None:
            word = bytes(data[model_at : model_at + 2])
            big = link.family.byte_order == "big"
            model_register = int.from_bytes(word, "big" if big else "little")
    return Evidence(servo_id, baud, pings, reads, info, tuple(models), model_register, firmware)


def _layout(link: Link, model_number: int) -> tuple[Register | None, int | None, int]:
    """Present Position, the Model Number address and the Firmware Version address of
    ``model_number`` (its table's: the model at 0 and firmware at 2 on an AX, 6 on the X series,
    the model at 3 and firmware at 0 on a Feetech STS; for a model snakebot has no data for: no
    position, no model register to compare, the protocol's firmware address)."""
    try:
        table = table_for_model(model_number)
    except SnakebotError:
        return None, None, link.family.firmware_address
    return (
        table["present_position"],
        table["model_number"].address,
        table["firmware_version"].address,
    )


def _ask(
    link: Link, servo_id: int, address: int, length: int, tries: int = TRIES
) -> tuple[Tally, list[int] | None]:
    """Read until one clean reply: the tally and the clean data (None if none came).

    A read that gets no reply at all ends the questions (Status Return Level 0 answers pings
    only, and silence says nothing about collisions).
    """
    corrupt = 0
    for _ in range(tries):
        data, result = link.raw_read(servo_id, address, length)
        if result == sdk.COMM_SUCCESS and len(data) == length:
            return Tally(1, corrupt, 0), list(data)
        if result != sdk.COMM_SUCCESS and result not in CORRUPT:
            return Tally(0, corrupt, 1), None
        corrupt += 1  # damaged, or a status packet of the wrong length
    return Tally(0, corrupt, 0), None


def judge(evidence: Evidence) -> Verdict:
    """One servo, two servos on one ID, an ID whose every reply was corrupt, or nobody."""
    if not evidence.answered:
        return Verdict(Kind.ABSENT)
    if not evidence.clean:
        n = evidence.pings.corrupt
        return Verdict(Kind.GARBLED, f"all {n} ping replies were corrupt")
    models = sorted(set(evidence.models))
    if len(models) > 1:
        listed = ", ".join(map(str, models))
        return Verdict(Kind.SHARED, f"ping replies name different models ({listed})")
    reads = evidence.reads
    if reads.clean == 0 and reads.corrupt >= TRIES:
        return Verdict(
            Kind.SHARED,
            f"pings came back clean but all {reads.corrupt} reads of Present Position were "
            "corrupt: servos of one model answer together and their shafts differ",
        )
    register = evidence.model_register
    if register is not None and register != models[0]:
        return Verdict(
            Kind.SHARED, f"ping says model {models[0]}, the Model Number register says {register}"
        )
    return Verdict(Kind.ONE_SERVO)


def collision_reason(link: Link, servo_id: int, baud: int) -> str | None:
    """Why the replies of ``servo_id`` at ``baud`` look like several servos; None if like one
    (or like none). An ID whose every reply is corrupt counts as shared here."""
    verdict = judge(gather(link, servo_id, baud))
    return verdict.reason if verdict.kind in (Kind.SHARED, Kind.GARBLED) else None
