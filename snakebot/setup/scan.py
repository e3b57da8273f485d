"""Find every servo on a port, per protocol and baud rate: a first pass, then each ID on its own.

The first pass is a broadcast ping where the protocol has one (Dynamixel 2.0), else a ping of
every ID in the range, one by one (Dynamixel 1.0 and Feetech have no broadcast ping: each absent
ID costs the SDK's reply timeout, about 34 ms (Feetech's SDK: 50 ms), so 254 IDs take about 8.7 s
per rate on a real port).

Dynamixel Protocol 1.0 and Feetech's protocol frame their packets alike, so a servo of either
answers the other's ping; its model number, read where the family keeps it (address 0 on a
Dynamixel, 3 on a Feetech), names a model only in its own family. Where the same ID at the same
rate answered in two such families, the entry whose model number its family knows is kept.

The broadcast ping drops any reply slot it cannot parse, so a servo whose slot was lost (to noise
or a collision) and two servos sharing an ID both vanish from it. Hence every ID it lists, ID 1
(where new servos collide), and the IDs up to two past the highest one that answers are asked on
their own (:func:`snakebot.setup.duplicates.gather`). When the broadcast ping was left with
garbage that none of those explains, the remaining IDs are pinged one by one.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from snakebot.errors import SnakebotError
from snakebot.families import ServoFamily
from snakebot.servo import FACTORY_ID
from snakebot.servo_tables import table_for_model
from snakebot.setup.duplicates import Evidence, Kind, Verdict, gather, judge
from snakebot.setup.link import Link

LOOK_PAST = 2
"""IDs asked past the highest one that answered (a lost slot at the end of the chain)."""
SWEEP_S_PER_ID = 0.034
"""What an unanswered ping costs on a real port: the SDK's reply timeout (2 x 16 ms latency timer
+ 2 ms), plus the request's own bytes (:func:`sweep_seconds`)."""
PING_BYTES = 10  # a Protocol 1.0 ping is 6 bytes, 2.0's 10: the estimate takes the longer


def sweep_seconds(n_ids: int, baud: int) -> float:
    """Seconds ``n_ids`` unanswered pings take on a real port at ``baud`` (10 bits a byte)."""
    return n_ids * (SWEEP_S_PER_ID + PING_BYTES * 10 / baud)


Notify = Callable[[str], None]


@dataclass(frozen=True)
class ScanEntry:
    """One ID at one baud rate, in one protocol (``family``), that answered at all.

    ``verdict`` says whether it is one servo, two sharing the ID, or an ID whose every reply was
    corrupt; ``in_broadcast`` whether the first pass (the broadcast ping, or the ping sweep of a
    protocol without one) found it; ``corrupt``/``replies``
    count its corrupt replies among all it sent.
    """

    servo_id: int
    baud: int
    model_number: int
    firmware: int
    verdict: Verdict
    in_broadcast: bool
    corrupt: int
    replies: int
    family: ServoFamily

    @property
    def line(self) -> tuple[str, int]:
        """(family name, baud rate): the servos that hear each other."""
        return self.family.name, self.baud

    @property
    def known_model(self) -> bool:
        """Whether the model number names a model of the entry's family."""
        try:
            return self.family.speaks(table_for_model(self.model_number))
        except SnakebotError:
            return False

    @property
    def shared(self) -> bool:
        """Whether clean replies contradict each other: two servos answer to this ID."""
        return self.verdict.kind is Kind.SHARED

    @property
    def garbled(self) -> bool:
        """Whether every reply to this ID was corrupt."""
        return self.verdict.kind is Kind.GARBLED


@dataclass(frozen=True)
class ScanReport:
    """Every ID that answered, in protocol (as searched), baud and ID order."""

    entries: tuple[ScanEntry, ...]

    @property
    def bad_lines(self) -> list[tuple[str, int]]:
        """(family name, baud) pairs at which several IDs answered and not one reply came back
        clean: the line is at fault (wiring, termination, a rate the wiring cannot hold), not
        shared IDs."""
        lines = list(dict.fromkeys(e.line for e in self.entries))
        return [
            line
            for line in lines
            if len([e for e in self.entries if e.line == line]) >= 2
            and all(e.verdict.kind is Kind.GARBLED for e in self.entries if e.line == line)
        ]

    @property
    def problems(self) -> list[ScanEntry]:
        """Entries that look like two servos on one ID (outside the bad lines)."""
        bad = self.bad_lines
        return [
            e
            for e in self.entries
            if e.verdict.kind in (Kind.SHARED, Kind.GARBLED) and e.line not in bad
        ]

    @property
    def noisy(self) -> list[ScanEntry]:
        """Single servos that sent corrupt replies now and then (line noise)."""
        return [e for e in self.entries if e.verdict.kind is Kind.ONE_SERVO and e.corrupt]

    @property
    def protocols(self) -> tuple[float, ...]:
        """The protocols that single servos answered in, in search order."""
        return tuple(
            dict.fromkeys(
                e.family.protocol for e in self.entries if e.verdict.kind is Kind.ONE_SERVO
            )
        )

    @property
    def families(self) -> tuple[ServoFamily, ...]:
        """The families that single servos answered in, in search order."""
        return tuple(
            dict.fromkeys(e.family for e in self.entries if e.verdict.kind is Kind.ONE_SERVO)
        )

    @property
    def mixed(self) -> bool:
        """Whether servos of more than one family share the port (one bus speaks one)."""
        return len(self.families) > 1


def scan(
    link: Link,
    plan: Sequence[tuple[ServoFamily, Sequence[int]]],
    *,
    ids: Sequence[int] | None = None,
    notify: Notify = lambda _text: None,
) -> ScanReport:
    """Every servo answering on ``link``, for each (family, baud rates) of ``plan`` in turn.

    ``ids`` bounds the one-by-one pings (a protocol without a broadcast ping; the fallback after
    a garbled broadcast ping); default every ID the family has. ``notify`` hears about slow
    sweeps before they start.
    """
    entries: list[ScanEntry] = []
    swept: dict[tuple[str, int], set[int]] = {}
    for family, bauds in plan:
        link.speak(family)
        wanted = tuple(range(family.max_id + 1)) if ids is None else tuple(ids)
        for baud in bauds:
            heard = swept.get((family.framing, baud)) if family.framing else None
            found = _scan_baud(link, family, baud, wanted, notify, heard)
            entries += found
            if heard is None and not family.broadcast_ping and family.framing:
                swept[(family.framing, baud)] = {e.servo_id for e in found}
    return ScanReport(tuple(_one_family_each(entries)))


def _one_family_each(entries: list[ScanEntry]) -> list[ScanEntry]:
    """One entry per servo where an ID at a rate answered in several families of one framing (a
    Feetech servo answers a Dynamixel 1.0 ping): the ones whose model number their family knows,
    else the first searched (a model snakebot has no data for reads as such in every family)."""
    groups: dict[tuple[int, int, str], list[ScanEntry]] = {}
    for entry in entries:
        if entry.verdict.kind is Kind.ONE_SERVO and entry.family.framing:
            key = (entry.servo_id, entry.baud, entry.family.framing)
            groups.setdefault(key, []).append(entry)
    dropped: set[int] = set()
    for group in groups.values():
        known = [e for e in group if e.known_model] or group[:1]
        dropped |= {id(e) for e in group if e not in known}
    return [e for e in entries if id(e) not in dropped]


def _first_pass(
    link: Link,
    family: ServoFamily,
    baud: int,
    ids: Sequence[int],
    notify: Notify,
    heard: set[int] | None = None,
) -> tuple[dict[int, tuple[int, int]], set[int], bool]:
    """The IDs found at first sight ``{id: (model, firmware or 0)}``, the IDs whose reply was
    corrupt, and whether the broadcast ping was left with garbage it could not place.

    ``heard``: the IDs that answered a ping sweep at this rate in another family of the same
    framing (the same ping packet): only those are pinged again."""
    if family.broadcast_ping:
        pinged, garbled = link.broadcast(baud)
        return pinged, set(), garbled
    if heard is not None:
        ids = [i for i in ids if i in heard]
    else:
        notify(
            f"{family.label} has no broadcast ping: pinging IDs {_span(ids)} one by "
            f"one at {baud} baud (about {sweep_seconds(len(ids), baud):.1f} s on a real port; "
            "--ids bounds it)"
        )
    found: dict[int, tuple[int, int]] = {}
    corrupt: set[int] = set()
    for servo_id in ids:
        probe = link.probe(servo_id, baud, tries=1)
        if probe.models:
            found[servo_id] = (probe.models[0], 0)
        elif probe.corrupt:
            corrupt.add(servo_id)
    return found, corrupt, False


def _span(ids: Sequence[int]) -> str:
    if ids and list(ids) == list(range(ids[0], ids[-1] + 1)):
        return f"{ids[0]}..{ids[-1]}"
    return ", ".join(map(str, ids))


def _scan_baud(
    link: Link,
    family: ServoFamily,
    baud: int,
    ids: Sequence[int],
    notify: Notify,
    heard: set[int] | None = None,
) -> list[ScanEntry]:
    pinged, suspects, garbled = _first_pass(link, family, baud, ids, notify, heard)
    evidence: dict[int, Evidence] = {}
    highest = max(pinged, default=0)
    todo = {*pinged, *suspects, FACTORY_ID, *range(1, highest + LOOK_PAST + 1)}
    while todo:
        servo_id = min(todo)
        todo.discard(servo_id)
        found = gather(link, servo_id, baud, patient=servo_id in pinged)
        evidence[servo_id] = found
        if found.answered and servo_id >= highest:
            highest = servo_id
            todo |= {i for i in range(servo_id + 1, servo_id + LOOK_PAST + 1) if i <= family.max_id}
            todo -= set(evidence)
    explained = any(e.answered for i, e in evidence.items() if i not in pinged)
    if garbled and not explained and family.broadcast_ping:
        rest = [i for i in ids if i not in evidence]
        notify(
            f"the broadcast ping at {baud} baud was left with garbled replies that no ID up to "
            f"{highest + LOOK_PAST} explains: pinging the other {len(rest)} IDs one by one "
            f"(about {sweep_seconds(len(rest), baud):.0f} s on a real port)"
        )
        for servo_id in rest:
            evidence[servo_id] = gather(link, servo_id, baud)
    return [
        _entry(found, pinged.get(servo_id), family)
        for servo_id, found in sorted(evidence.items())
        if found.answered or servo_id in pinged
    ]


def _entry(found: Evidence, pinged: tuple[int, int] | None, family: ServoFamily) -> ScanEntry:
    verdict = judge(found)
    model, firmware = pinged or (0, 0)
    if verdict.kind is Kind.ABSENT and pinged is not None:
        verdict = Verdict(
            Kind.ONE_SERVO,
            f"answered the first ping but none of {found.pings.silent} pings on its own",
        )
    if verdict.kind is Kind.ONE_SERVO:
        model = model or (found.models[0] if found.models else 0)
        firmware = firmware or (found.firmware or 0)
    else:
        model = firmware = 0
    return ScanEntry(
        found.servo_id,
        found.baud,
        model,
        firmware,
        verdict,
        pinged is not None,
        found.corrupt,
        found.replies,
        family,
    )
