"""Give one servo its ID and baud rate: the factory-fresh servo flow (every new one is ID 1, at its
model's factory rate: 57600 on the X series and the MX, 1 Mbps on the AX).

The servo is searched for at every baud rate its model has: by a broadcast ping where the family
has one, else by pinging every ID on its own (Protocol 1.0; about 8.7 s per rate on a real port,
so naming the ID, ``from_id``, is much quicker). Without ``from_id`` it must be the only servo on
the bus; with it, the only one answering as that ID. The target ID must be free, both at the rate
the servo is at and at the rate it moves to. The ID changes first, the baud rate last, each verified
by finding the servo again. Where the family locks its EEPROM (Feetech: Lock 1 at power-on, when an
ID written acts until the next power-off only and the servo is back at ID 1 after it), the lock is
opened before each write and closed again at the servo's new ID and rate.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

from snakebot.servo import FACTORY_ID
from snakebot.servo_tables import ServoTable, table_for_model
from snakebot.setup.bauds import baud_value, factory_baud, model_bauds
from snakebot.setup.duplicates import collision_reason
from snakebot.setup.errors import DuplicateIdError, SetupError, VerifyError
from snakebot.setup.link import Link, unanswered_ok
from snakebot.setup.maintenance import wait_for_boot

LATE_REPLY_S = 0.1
"""How long a verify waits for a late reply to pass before it reads again."""


@dataclass(frozen=True)
class Found:
    """A servo that answered: its ID, the rate it answered at and its model number."""

    servo_id: int
    baud: int
    model_number: int


@dataclass(frozen=True)
class Assignment:
    """What assign-id did: the servo as found, and its ID and baud rate now."""

    found: Found
    servo_id: int
    baud: int

    @property
    def changed(self) -> bool:
        """Whether anything was written."""
        return (self.servo_id, self.baud) != (self.found.servo_id, self.found.baud)


def search_bauds(link: Link) -> tuple[int, ...]:
    """The rates a servo of the link's model can be at, its factory rate first."""
    return model_bauds(link.bus.table)


def find_servos(
    link: Link, *, from_id: int | None = None, bauds: Sequence[int] | None = None
) -> list[Found]:
    """Every servo answering (as ``from_id``, if given) at ``bauds`` (default: every rate of
    the link's model); DuplicateIdError on clashes.

    Without ``from_id`` every ID is listed at each rate (:meth:`Link.listening`); ID 1 is always
    checked too, since new servos collide there.
    """
    found: list[Found] = []
    clashes: list[tuple[int, int, str]] = []
    for baud in search_bauds(link) if bauds is None else bauds:
        ids = {from_id} if from_id is not None else {FACTORY_ID, *link.listening(baud)}
        for servo_id in sorted(ids):
            reason = collision_reason(link, servo_id, baud)
            if reason:
                clashes.append((servo_id, baud, reason))
                continue
            model = link.ping_clean(servo_id, baud, tries=1)
            if model is not None:
                found.append(Found(servo_id, baud, model))
    if clashes:
        raise DuplicateIdError(link.port, clashes)
    return found


def _describe(found: Sequence[Found]) -> str:
    return ", ".join(f"ID {f.servo_id} at {f.baud} baud" for f in found)


def _table(link: Link, servo: Found) -> ServoTable:
    try:
        return table_for_model(servo.model_number)
    except LookupError as exc:
        raise SetupError(f"{link.port}: the servo is model {servo.model_number}: {exc}") from None


def _lone(link: Link, found: list[Found], from_id: int | None, bauds: Sequence[int]) -> Found:
    who = "no servo" if from_id is None else f"no servo as ID {from_id}"
    table = link.bus.table
    if not found:
        raise SetupError(
            f"{link.port}: {who} answered at any baud rate ({', '.join(map(str, bauds))}) in "
            f"{link.family.label}. Check the servo's power (its LED blinks once "
            "at power-up) and cable"
        )
    if len(found) > 1:
        hint = (
            (
                "connect only the new servo, or name the ID to change (option from_id; a new "
                f"{table.model} is ID {table['id'].default} at {factory_baud(table)})"
            )
            if from_id is None
            else "unplug all but the one to change"
        )
        raise SetupError(
            f"{link.port}: {len(found)} servos answer ({_describe(found)}); "
            f"assign-id changes one servo at a time: {hint}"
        )
    return found[0]


def _check_free(link: Link, servo: Found, to_id: int, bauds: set[int]) -> None:
    for baud in sorted(bauds):
        if to_id == servo.servo_id and baud == servo.baud:
            continue
        probe = link.probe(to_id, baud, tries=1)
        if probe.models or probe.corrupt:
            raise SetupError(
                f"{link.port}: ID {to_id} is taken: a servo already answers as ID {to_id} at "
                f"{baud} baud. Pick another new ID (option to), or move that servo first"
            )


def assign_id(
    link: Link,
    *,
    to_id: int,
    baud: int,
    from_id: int | None = None,
    bauds: Sequence[int] | None = None,
    dry_run: bool = False,
) -> Assignment:
    """Find the lone servo, then set its ID to ``to_id`` and its rate to ``baud`` (verified).

    ``dry_run``: every check (one servo, a supported rate, the ID free) and no write; the
    Assignment says what would be set. SetupError (or DuplicateIdError) says why not.
    """
    bauds = search_bauds(link) if bauds is None else bauds
    servo = _lone(link, find_servos(link, from_id=from_id, bauds=bauds), from_id, bauds)
    table = _table(link, servo)
    try:
        index = baud_value(table, baud)
    except ValueError as exc:
        raise SetupError(f"baud rate {baud}: {exc}") from None
    _check_free(link, servo, to_id, {servo.baud, baud})
    if dry_run:
        return Assignment(servo, to_id, baud)
    link.bus.table = table
    bus = link.at(servo.baud)
    if (to_id, baud) != (servo.servo_id, servo.baud) and bus.read(servo.servo_id, "torque_enable"):
        bus.write(servo.servo_id, "torque_enable", 0)  # ID and Baud Rate are EEPROM items
    if to_id != servo.servo_id:
        link.unlock(servo.servo_id, servo.baud)
        with unanswered_ok():  # the reply may already carry the new ID
            link.at(servo.baud).write(servo.servo_id, "id", to_id)
        _verify(link, to_id, servo.baud, "id", to_id)
        link.relock(to_id, servo.baud)
    if baud != servo.baud:
        link.unlock(to_id, servo.baud)
        with unanswered_ok():  # the reply may already come at the new rate
            link.at(servo.baud).write(to_id, "baud_rate", index)
        _verify(link, to_id, baud, "baud_rate", index)
        link.relock(to_id, baud)
    return Assignment(servo, to_id, baud)


def _verify(link: Link, servo_id: int, baud: int, key: str, value: int) -> None:
    try:
        wait_for_boot(link, servo_id, baud, timeout_s=1.0)
    except SetupError:
        raise SetupError(
            f"{link.port}: after writing {key} the servo does not answer as ID {servo_id} at "
            f"{baud} baud; `snakebot scan --all-bauds` finds it"
        ) from None
    back = link.at(baud).read(servo_id, key)
    if back != value:
        # A reply that came late to one of the pings above can answer this read instead (the SDK
        # pairs replies with requests by order only; seen over a loaded pty: 36, the low byte of
        # model 1060): let it pass and ask once more. A value really not taken reads wrong again.
        time.sleep(LATE_REPLY_S)
        back = link.at(baud).read(servo_id, key)
    if back != value:
        raise VerifyError(link.port, servo_id, key, value, back)
