"""Seeded fuzzing of the emulated Dynamixel bus, in-process and over a real pseudo-terminal.

Each input (tools/fuzz_packets.py: random bytes, field-aware packets, bit flips, truncations,
wrong and huge lengths, stuffing edge cases, bad CRCs, splices) goes to a chain of three XL430
servos (IDs 1-3), followed by 1024 zero bytes whenever it could leave a packet half-received.
With `--protocol 1` the inputs are Protocol 1.0 ones (tools/fuzz_packets1.py: the same families
with checksums instead of CRCs and Protocol 2.0 packets mixed in instead of stuffing cases), sent
to two AX-12As and an XL430 in Protocol 1.0 mode, followed by 256 zero bytes. With `--protocol
feetech` they are Feetech FT-SCS ones (tools/fuzz_packets_feetech.py: Protocol 1.0's framing with
Feetech's instruction set and items) sent to two STS3215s and an SCS0009, probed over the pty
through the stock `scservo_sdk`. Then the campaign checks:

- crash: the chain raised (in-process) or the pty server thread died;
- hang: the chain spent over 1 s of CPU on one input, or answered nothing (input or probe) for
  30 s (on a loaded machine a starved emulator is slow, not hung: the slowest input's wall time
  is reported);
- corruption: a probe (a ping and a read of Model Number, one servo in turn) was not answered
  exactly right; a servo that no valid packet in the input addressed with a write-like
  instruction changed a control-table byte (present values aside); an input without any valid
  packet got a reply (in Protocol 1.0, other than a Checksum-error status from the servo a
  damaged frame names); a reply packet outgrew 1024 bytes (250 in Protocol 1.0); a lone
  unicast Write the servo rejected changed its table, or one it accepted is not in its table
  (in-process, where the replies are seen); a Feetech status cannot say a write was refused, so
  there a lone Write must be stored whole or not at all.

State a valid input changed legitimately is put back (fresh servos) before the probe. "Valid"
is judged by tools/fuzz_packets.candidates, which uses the SDK's CRC, not the emulator's.

Usage: python tools/fuzz_emulator.py [--packets 100000] [--seed 1] [--transport inproc|pty|both]
       [--protocol 2|1|feetech] [--pty-packets N] [--json] [--replay INDEX]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import fuzz_packets1
import fuzz_packets_feetech
from fuzz_packets import (
    BROADCAST,
    READ_ONLY,
    RESET,
    WRITE,
    Candidate,
    Inputs,
    candidates,
    may_leave_partial,
)
from fuzz_targets import (
    FEETECH,
    IDS,
    CrashError,
    HangError,
    InProcess,
    OverPty,
    Tables,
    Target,
    make_servos,
)

from snakebot.emulation import VirtualServo
from snakebot.emulation.protocol import MAX_PACKET_BYTES

FILLER = bytes(MAX_PACKET_BYTES)
VOLATILE = (
    "realtime_tick",
    "moving",
    "moving_status",
    "present_pwm",
    "present_load",
    "present_current",
    "present_velocity",
    "present_position",
    "velocity_trajectory",
    "position_trajectory",
    "present_input_voltage",
    "present_temperature",
    "present_goal_position",
)
IDENTITY = (7, 8, 12, 13, 68)  # ID, baud, secondary ID, protocol, status return level
IDENTITY_P1 = (3, 4, 16, *IDENTITY)  # AX-12A ID, baud, status return level; and the X table's
IDENTITY_FEETECH = (5, 6, 8)  # ID, baud, response status level
GOAL_ITEMS = ("goal_pwm", "goal_current", "goal_velocity", "goal_position")
P1_REJECTIONS = 0x02 | 0x08 | 0x40  # angle limit, range, instruction bits


@dataclass(frozen=True)
class Dialect:
    """What the campaign needs to know of one protocol's packets."""

    protocol: int
    inputs: Any
    candidates: Callable[[bytes], list[Candidate]]
    may_leave_partial: Callable[[bytes], bool]
    filler: bytes
    read_only: frozenset[int]
    identity: tuple[int, ...]
    address_bytes: int
    max_reply: int
    reports_rejection: bool = True
    """Whether a status says a write was refused (a Feetech status byte cannot)."""

    @property
    def name(self) -> str:
        """How reports name the protocol."""
        return "Feetech" if self.protocol == FEETECH else f"Protocol {self.protocol}"

    def write_target(self, params: bytes) -> tuple[int, bytes]:
        """(address, data) of a Write's parameters."""
        if self.address_bytes == 1:
            return params[0], params[1:]
        return params[0] | params[1] << 8, params[2:]

    def answers_damage(self, status: Candidate) -> bool:
        """Whether a status answers a damaged frame (Protocol 1.0's Checksum bit), not a
        valid instruction."""
        return self.protocol == 1 and bool(status.instruction & fuzz_packets1.CHECKSUM_BIT)

    def rejected(self, status: Candidate) -> int:
        """The error a status reports for the instruction (not the alarms it carries)."""
        if self.protocol == FEETECH:
            return 0
        if self.protocol == 1:
            return status.instruction & P1_REJECTIONS
        return status.params[0] & 0x7F if status.params else 0


def dialect(protocol: int) -> Dialect:
    """The packets of Protocol `protocol` (2 or 1, or FEETECH)."""
    if protocol == FEETECH:
        return Dialect(
            FEETECH,
            fuzz_packets_feetech.InputsFeetech(IDS),
            fuzz_packets1.candidates,
            fuzz_packets1.may_leave_partial,
            bytes(256),
            fuzz_packets_feetech.READ_ONLY,
            IDENTITY_FEETECH,
            1,
            fuzz_packets1.MAX_PACKET,
            reports_rejection=False,
        )
    if protocol == 1:
        return Dialect(
            1,
            fuzz_packets1.Inputs1(IDS),
            fuzz_packets1.candidates,
            fuzz_packets1.may_leave_partial,
            bytes(256),
            fuzz_packets1.READ_ONLY,
            IDENTITY_P1,
            1,
            fuzz_packets1.MAX_PACKET,
        )
    return Dialect(
        2, Inputs(IDS), candidates, may_leave_partial, FILLER, READ_ONLY, IDENTITY, 2, 1024
    )


MODE_RESETS = (
    "velocity_i_gain",
    "velocity_p_gain",
    "position_d_gain",
    "position_i_gain",
    "position_p_gain",
    "profile_acceleration",
    "profile_velocity",
    "goal_pwm",
    "goal_current",
)


class Layout:
    """Which bytes of the table count as state, and which belong to which item."""

    def __init__(self, servo: VirtualServo) -> None:
        memory = servo.memory
        self.size = len(memory.data)
        self.volatile = bytearray(self.size)
        self.owner: list[str | None] = [None] * self.size
        for register in memory.items.values():
            for address in range(register.address, register.address + register.size):
                self.owner[address] = register.key
                if register.key in VOLATILE:
                    self.volatile[address] = 1

        self.stable: list[tuple[int, int]] = []  # runs of addresses that are not volatile
        start = None
        for address in range(self.size + 1):
            steady = address < self.size and not self.volatile[address]
            if steady and start is None:
                start = address
            elif not steady and start is not None:
                self.stable.append((start, address))
                start = None

    def changed(self, before: bytes, after: bytes) -> list[int]:
        """Addresses whose byte changed, present values aside."""
        if before == after or all(before[a:b] == after[a:b] for a, b in self.stable):
            return []
        return [a for a in range(self.size) if before[a] != after[a] and not self.volatile[a]]


@dataclass
class Report:
    """What a campaign found."""

    transport: str
    seed: int
    protocol: int = 2
    packets: int = 0
    seconds: float = 0.0
    crashes: int = 0
    hangs: int = 0
    corruptions: int = 0
    slowest_s: float = 0.0
    families: Counter[str] = field(default_factory=Counter)
    kinds: Counter[str] = field(default_factory=Counter)
    examples: list[dict[str, Any]] = field(default_factory=list)

    def note(self, what: str, kind: str, index: int, family: str, data: bytes, detail: str) -> None:
        setattr(self, what, getattr(self, what) + 1)
        self.kinds[kind] += 1
        if len(self.examples) < 20:
            self.examples.append(
                {
                    "index": index,
                    "family": family,
                    "kind": kind,
                    "input": data.hex(" "),
                    "detail": detail[-2000:],
                }
            )

    def as_dict(self) -> dict[str, Any]:
        rate = self.packets / self.seconds if self.seconds else 0.0
        return {
            "transport": self.transport,
            "seed": self.seed,
            "protocol": self.protocol,
            "family": "feetech" if self.protocol == FEETECH else "dynamixel",
            "packets": self.packets,
            "seconds": round(self.seconds, 2),
            "packets_per_s": round(rate),
            "crashes": self.crashes,
            "hangs": self.hangs,
            "corruptions": self.corruptions,
            "slowest_input_s": round(self.slowest_s, 3),
            "kinds": dict(self.kinds),
            "families": dict(self.families),
            "examples": self.examples,
        }


class Campaign:
    """Runs inputs of campaign `seed` against one target, noting what goes wrong in `report`."""

    def __init__(self, target: Target, seed: int, report: Report, protocol: int = 2) -> None:
        self.target = target
        self.seed = seed
        self.report = report
        self.dialect = dialect(protocol)
        self.inputs = self.dialect.inputs
        self.layouts = [Layout(servo) for servo in make_servos(1_000_000, protocol)]
        self.baseline = self.target.tables().memory

    def run(self, indices: range) -> None:
        start = time.perf_counter()
        for index in indices:
            self.one(index)
        self.report.seconds += time.perf_counter() - start
        self.report.packets += len(indices)

    def one(self, index: int) -> None:
        family, data = self.inputs.make(self.seed, index)
        self.report.families[family] += 1
        sent = data + self.dialect.filler if self.dialect.may_leave_partial(data) else data
        before = self.target.tables()
        began = time.perf_counter()
        try:
            replies, after = self.target.send(sent)
        except HangError as exc:
            self._fail("hangs", "input not taken in", index, family, data, str(exc))
            return
        except CrashError as exc:
            self._fail("crashes", "chain raised", index, family, data, str(exc))
            return
        self.report.slowest_s = max(self.report.slowest_s, time.perf_counter() - began)
        for kind, detail in self.judge(sent, before, after, replies):
            self.report.note("corruptions", kind, index, family, data, detail)
        if any(
            layout.changed(b, a)
            for layout, b, a in zip(self.layouts, self.baseline, after.memory, strict=False)
        ) or len(after.memory) != len(self.baseline):
            self.target.restore()
        try:
            self.target.probe(IDS[index % len(IDS)])
        except HangError as exc:
            self._fail("hangs", "probe unanswered", index, family, data, str(exc))
        except AssertionError as exc:
            self.report.note("corruptions", "probe", index, family, data, str(exc))
            self.target.restore()

    def _fail(
        self, what: str, kind: str, index: int, family: str, data: bytes, detail: str
    ) -> None:
        self.report.note(what, kind, index, family, data, detail)
        self.target.restart()

    def judge(
        self, sent: bytes, before: Tables, after: Tables, replies: list[bytes] | None
    ) -> list[tuple[str, str]]:
        """Corruption findings for one input (see the module docstring)."""
        found = self.dialect.candidates(sent)
        problems: list[tuple[str, str]] = []
        if replies is not None:
            if not found and replies and not self._checksum_replies(sent, replies):
                problems.append(("reply to garbage", b"".join(replies).hex(" ")))
            if _long_header(b"".join(replies)) or any(
                len(r) > self.dialect.max_reply for r in replies
            ):
                problems.append(("oversized reply", f"a packet over {self.dialect.max_reply}"))
        writers = [c for c in found if c.instruction not in self.dialect.read_only]
        identities = list(before.identities)
        addressed = _addressed(writers, identities, self.dialect)
        for number, (old, new) in enumerate(zip(before.memory, after.memory, strict=False)):
            changed = self.layouts[number].changed(old, new)
            if changed and number not in addressed:
                problems.append(
                    (
                        "unexplained change",
                        f"servo #{number} (ID {identities[number][0]}) bytes {changed}",
                    )
                )
        if replies is not None and len(writers) == 1 and writers[0].instruction == WRITE:
            problems += self._check_write(
                writers[0], found, identities, before.memory, after.memory, replies
            )
        return problems

    def _checksum_replies(self, sent: bytes, replies: list[bytes]) -> bool:
        """Protocol 1.0: whether every reply is a Checksum-error status from a servo that a
        damaged frame in `sent` names (the only reply an input without a valid packet gets)."""
        if self.dialect.protocol != 1:
            return False
        statuses = fuzz_packets1.candidates(b"".join(replies))
        framed = fuzz_packets1.framed_ids(sent)
        return (
            bool(statuses)
            and len(statuses) == len(replies)
            and all(
                s.instruction & fuzz_packets1.CHECKSUM_BIT and s.servo_id in framed
                for s in statuses
            )
        )

    def _check_write(
        self,
        write: Candidate,
        found: list[Candidate],
        identities: list[tuple[int, int | None]],
        before: tuple[bytes, ...],
        after: tuple[bytes, ...],
        replies: list[bytes],
    ) -> list[tuple[str, str]]:
        """The lone write of an input: rejected, nothing changed; accepted, its bytes stored."""
        owners = [n for n, (servo_id, _) in enumerate(identities) if servo_id == write.servo_id]
        others = [c for c in found if c is not write and c.servo_id in (write.servo_id, BROADCAST)]
        statuses = [
            s
            for s in self.dialect.candidates(b"".join(replies))
            if s.servo_id == write.servo_id and not self.dialect.answers_damage(s)
        ]
        if (
            len(owners) != 1
            or others
            or len(statuses) != 1
            or len(write.params) < self.dialect.address_bytes + 1
        ):
            return []
        number = owners[0]
        layout = self.layouts[number]
        error = self.dialect.rejected(statuses[0])
        if error:
            changed = layout.changed(before[number], after[number])
            return (
                [("rejected write changed state", f"error {error}, bytes {changed}")]
                if changed
                else []
            )
        address, data = self.dialect.write_target(write.params)
        keys = {layout.owner[a] for a in range(address, address + len(data)) if a < layout.size}
        skip = {"torque_enable"} if keys & set(GOAL_ITEMS) else set()
        skip |= set(MODE_RESETS) if "operating_mode" in keys else set()
        if not self.dialect.reports_rejection:
            return self._whole_or_nothing(address, data, layout, before[number], after[number])
        wrong = [
            a
            for a, byte in zip(range(address, address + len(data)), data, strict=False)
            if a < layout.size
            and (key := layout.owner[a]) is not None
            and not key.startswith("indirect_data")
            and key not in skip
            and after[number][a] != byte
        ]
        return [("accepted write not stored", f"addresses {wrong}")] if wrong else []

    @staticmethod
    def _whole_or_nothing(
        address: int, data: bytes, layout: Layout, before: bytes, after: bytes
    ) -> list[tuple[str, str]]:
        """A write no status can call refused: its item bytes all stored, or none changed
        (Torque Enable aside: 128 calibrates and reads 0, a goal turns the torque on)."""
        spots = [
            (a, byte)
            for a, byte in zip(range(address, address + len(data)), data, strict=False)
            if a < layout.size
            and layout.owner[a] not in (None, "torque_enable")
            and not layout.volatile[a]
        ]
        stored = all(after[a] == byte for a, byte in spots)
        untouched = all(after[a] == before[a] for a, _ in spots)
        if stored or untouched:
            return []
        partial = [a for a, byte in spots if after[a] != byte]
        return [("write stored in part", f"addresses {partial} not as written")]


def _addressed(
    writers: list[Candidate], identities: list[tuple[int, int | None]], dialect: Dialect
) -> set[int]:
    """Servos (by position) that the write-like packets may have changed."""
    everyone = set(range(len(identities)))
    if any(
        c.servo_id == BROADCAST or c.instruction == RESET or _touches_identity(c, dialect)
        for c in writers
    ):
        return everyone
    ids = {c.servo_id for c in writers}
    return {
        n for n, (servo_id, shadow) in enumerate(identities) if servo_id in ids or shadow in ids
    }


def _touches_identity(candidate: Candidate, dialect: Dialect) -> bool:
    if len(candidate.params) < dialect.address_bytes + 1:
        return False
    address, data = dialect.write_target(candidate.params)
    return any(address <= a < address + len(data) for a in dialect.identity)


def _long_header(data: bytes) -> bool:
    """Whether a status header in `data` announces more than a 1024-byte packet."""
    start = data.find(b"\xff\xff\xfd\x00")
    while start >= 0 and start + 8 <= len(data):
        if data[start + 7] == 0x55 and (data[start + 5] | data[start + 6] << 8) > 1017:
            return True
        start = data.find(b"\xff\xff\xfd\x00", start + 1)
    return False


def run_campaign(
    transport: str, seed: int, count: int, first: int = 0, protocol: int = 2
) -> Report:
    """Fuzz `count` inputs of campaign `seed` over `transport` ("inproc" or "pty") in
    Protocol `protocol` (2 or 1)."""
    target: Target = InProcess(protocol) if transport == "inproc" else OverPty(protocol)
    report = Report(transport, seed, protocol)
    try:
        Campaign(target, seed, report, protocol).run(range(first, first + count))
    finally:
        target.close()
    return report


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--packets", type=int, default=100_000, help="inputs per transport")
    parser.add_argument("--pty-packets", type=int, help="inputs over the pty (default --packets)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--transport", choices=("inproc", "pty", "both"), default="both")
    parser.add_argument(
        "--protocol",
        choices=("2", "1", "feetech"),
        default="2",
        help="the protocol of the inputs and the servos (default 2; feetech: Feetech FT-SCS)",
    )
    parser.add_argument("--replay", type=int, metavar="INDEX", help="run only input INDEX")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    protocol = FEETECH if args.protocol == "feetech" else int(args.protocol)
    transports = ("inproc", "pty") if args.transport == "both" else (args.transport,)
    reports = []
    for transport in transports:
        count = args.packets if transport == "inproc" else (args.pty_packets or args.packets)
        first = 0
        if args.replay is not None:
            count, first = 1, args.replay
        reports.append(run_campaign(transport, args.seed, count, first, protocol))
    summary = {
        "command": "python tools/fuzz_emulator.py " + " ".join(argv or sys.argv[1:]),
        "python": platform.python_version(),
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "reports": [r.as_dict() for r in reports],
    }
    if args.json:
        print(json.dumps(summary))
    else:
        for r in reports:
            d = r.as_dict()
            print(
                f"{d['transport']:>6}: {d['packets']} {dialect(d['protocol']).name} inputs "
                f"(seed {d['seed']}) in "
                f"{d['seconds']} s, {d['packets_per_s']}/s: {d['crashes']} crashes, "
                f"{d['hangs']} hangs, {d['corruptions']} corruptions {d['kinds'] or ''}"
            )
            for example in d["examples"][:5]:
                print(
                    f"  #{example['index']} {example['family']}: {example['kind']}: "
                    f"{example['detail'][:300]}\n    input: {example['input'][:200]}"
                )
    bad = sum(r.crashes + r.hangs + r.corruptions for r in reports)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
