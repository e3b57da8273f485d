"""Find every servo on a port: a broadcast ping per baud rate, then each ID asked on its own.

The broadcast ping drops any reply slot it cannot parse, so a servo whose slot was lost (to noise
or a collision) and two servos sharing an ID both vanish from it. Hence every ID it lists, ID 1
(where new servos collide), and the IDs up to two past the highest one that answers are asked on
their own (:func:`snakebot.setup.duplicates.gather`). When the broadcast ping was left with
garbage that none of those explains, the remaining IDs are pinged one by one.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from snakebot.servo import FACTORY_ID
from snakebot.setup.duplicates import Evidence, Kind, Verdict, gather, judge
from snakebot.setup.link import Link

MAX_ID = 252  # Protocol 2.0 device IDs are 0..252 (e-Manual protocol2, Packet ID)
LOOK_PAST = 2
"""IDs asked past the highest one that answered (a lost slot at the end of the chain)."""
SWEEP_S_PER_ID = 0.035
"""What an unanswered ping costs on a real port (the SDK's timeout), for the sweep estimate."""


@dataclass(frozen=True)
class ScanEntry:
    """One ID at one baud rate that answered at all.

    ``verdict`` says whether it is one servo, two sharing the ID, or an ID whose every reply was
    corrupt; ``in_broadcast`` whether the broadcast ping listed it; ``corrupt``/``replies``
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
    """Every ID that answered, in baud then ID order."""

    entries: tuple[ScanEntry, ...]

    @property
    def bad_lines(self) -> list[int]:
        """Baud rates at which several IDs answered and not one reply came back clean: the line
        is at fault (wiring, termination, a rate the wiring cannot hold), not shared IDs."""
        bauds = sorted({e.baud for e in self.entries})
        return [
            baud for baud in bauds
            if len([e for e in self.entries if e.baud == baud]) >= 2
            and all(e.verdict.kind is Kind.GARBLED for e in self.entries if e.baud == baud)
        ]

    @property
    def problems(self) -> list[ScanEntry]:
        """Entries that look like two servos on one ID (outside the bad lines)."""
        bad = self.bad_lines
        return [
            e for e in self.entries
            if e.verdict.kind in (Kind.SHARED, Kind.GARBLED) and e.baud not in bad
        ]

    @property
    def noisy(self) -> list[ScanEntry]:
        """Single servos that sent corrupt replies now and then (line noise)."""
        return [e for e in self.entries if e.verdict.kind is Kind.ONE_SERVO and e.corrupt]


def scan(
    link: Link, bauds: Sequence[int], *, notify: Callable[[str], None] = lambda _text: None
) -> ScanReport:
    """Every servo answering on ``link`` at ``bauds``; ``notify`` hears about slow sweeps."""
    entries: list[ScanEntry] = []
    for baud in bauds:
        entries += _scan_baud(link, baud, notify)
    return ScanReport(tuple(entries))


def _scan_baud(link: Link, baud: int, notify: Callable[[str], None]) -> list[ScanEntry]:
    pinged, garbled = link.broadcast(baud)
    evidence: dict[int, Evidence] = {}
    highest = max(pinged, default=0)
    todo = {*pinged, FACTORY_ID, *range(1, highest + LOOK_PAST + 1)}
    while todo:
        servo_id = min(todo)
        todo.discard(servo_id)
        found = gather(link, servo_id, baud, patient=servo_id in pinged)
        evidence[servo_id] = found
        if found.answered and servo_id >= highest:
            highest = servo_id
            todo |= {i for i in range(servo_id + 1, servo_id + LOOK_PAST + 1) if i <= MAX_ID}
            todo -= set(evidence)
    explained = any(e.answered for i, e in evidence.items() if i not in pinged)
    if garbled and not explained:
        rest = [i for i in range(MAX_ID + 1) if i not in evidence]
        notify(
            f"the broadcast ping at {baud} baud was left with garbled replies that no ID up to "
            f"{highest + LOOK_PAST} explains: pinging the other {len(rest)} IDs one by one "
            f"(about {len(rest) * SWEEP_S_PER_ID:.0f} s on a real port)"
        )
        for servo_id in rest:
            evidence[servo_id] = gather(link, servo_id, baud)
    return [
        _entry(found, pinged.get(servo_id))
        for servo_id, found in sorted(evidence.items())
        if found.answered or servo_id in pinged
    ]


def _entry(found: Evidence, pinged: tuple[int, int] | None) -> ScanEntry:
    verdict = judge(found)
    model, firmware = pinged or (0, 0)
    if verdict.kind is Kind.ABSENT and pinged is not None:
        verdict = Verdict(
            Kind.ONE_SERVO, f"answered the broadcast ping but none of {found.pings.silent} "
            "pings on its own"
        )
    if verdict.kind is Kind.ONE_SERVO:
        model = model or (found.models[0] if found.models else 0)
        firmware = firmware or (found.firmware or 0)
    else:
        model = firmware = 0
    return ScanEntry(
        found.servo_id, found.baud, model, firmware, verdict, pinged is not None,
        found.corrupt, found.replies,
    )
