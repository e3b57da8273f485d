"""`EmulatedChain`: servos on one half-duplex bus; instruction bytes in, timed status bytes out.

Transport-free: a transport feeds what the host wrote (`receive`) and delivers each `BusReply` at
its time; `advance` lets virtual time pass for the servos' motion and watchdogs. Faults are set
per servo (or per ID, for every servo carrying it) through the methods below.

Servos are stepped lazily: `advance` only counts time; each servo's step for the time passed runs
once, when something needs its state (a packet arrives, the chain's servos are looked up, or
`settle` is called), and in whole `STEP_S` steps once `SETTLE_AFTER_S` has piled up. A transport
that advances the chain once per reply byte group (a Fast Sync Read of N servos: N + 2 advances a
cycle) thus costs each servo two steps per cycle, not N + 2. How the time between two packets is
cut does not change the motion: it is stepped as whole `STEP_S` steps and one remainder.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Iterable, Sequence

from snakebot.emulation import (
    instructions,
    instructions1,
    instructions_feetech,
    protocol,
    protocol1,
)
from snakebot.emulation.alarms import Fault
from snakebot.emulation.case import cases_of
from snakebot.emulation.errors import EmulationError
from snakebot.emulation.faults import FaultBook, Faults
from snakebot.emulation.firmware import HardwareError
from snakebot.emulation.instructions import Slot
from snakebot.emulation.motion import STEP_S, ChainPhysics, MotionModel
from snakebot.emulation.stream import ParserStats
from snakebot.emulation.virtual_servo import VirtualServo
from snakebot.emulation.wire import BusReply, byte_time_s, merge_collisions
from snakebot.servo import FACTORY_BAUD
from snakebot.servo_tables import ServoTable, table_for_model

Target = int | VirtualServo
# A servo held from outside lags the bus clock by less than this (the Bus Watchdog counts in
# 20 ms units, so it still fires within one unit of its time).
SETTLE_AFTER_S = 0.01


_ONE_FRAMING: dict[str, Callable[[protocol1.Packet, Sequence[VirtualServo]], list[Slot]]] = {
    "dynamixel": instructions1.execute,
    "feetech": instructions_feetech.execute,
}
"""The instruction set that serves a Protocol 1.0-framed packet, by the servo's vendor."""


def _by_vendor(servos: list[VirtualServo]) -> dict[str, list[VirtualServo]]:
    grouped: dict[str, list[VirtualServo]] = {}
    for servo in servos:
        grouped.setdefault(servo.vendor, []).append(servo)
    return grouped


class EmulatedChain:
    """Several `VirtualServo`s sharing one bus at line rate `baud` (bit/s).

    A servo whose Baud Rate register gives another rate hears nothing. Feetech servos share
    Protocol 1.0's framing: its packets are served by each servo's vendor's instruction set
    (`VirtualServo.vendor`), so Dynamixel and Feetech servos may share a wire as they share
    the packet format. Both Dynamixel protocols share the
    wire: each servo answers only the packets of the protocol it speaks (`VirtualServo.protocol`:
    an X servo's Protocol Type, an AX always 1.0), so one chain may hold both kinds. Servos may
    share an ID: all of them execute what is sent to it and their replies
    collide on the wire. `physics`, when given, moves all servos at once (give them
    `ExternalMotion`). Thread-safe: every public method holds `lock`; hold it yourself to touch
    servos while a transport thread (PtyServer) serves the chain.
    """

    def __init__(
        self,
        servos: Iterable[VirtualServo] = (),
        *,
        baud: int = FACTORY_BAUD,
        seed: int = 0,
        stale_after_s: float = 0.02,
        physics: ChainPhysics | None = None,
    ) -> None:
        self._servos = list(servos)
        self.physics = physics
        self.baud = baud
        self.now_s = 0.0
        self.faults = FaultBook(seed)
        self.lock = threading.RLock()
        self._parser = protocol.StreamParser(stale_after_s=stale_after_s)
        self._parser1 = protocol1.StreamParser(stale_after_s=stale_after_s)
        self._unstepped_s = 0.0  # bus time the servos have not been stepped through yet
        self._judge_watchdog = True

    # ------------------------------------------------------------------ servos
    @property
    def servos(self) -> tuple[VirtualServo, ...]:
        """Every servo on the bus, in the order they were added, stepped up to now."""
        with self.lock:
            self.settle()
            return tuple(self._servos)

    def add(self, servo: VirtualServo) -> VirtualServo:
        """Connect a servo to the bus and return it."""
        with self.lock:
            self.settle()
            self._servos.append(servo)
        return servo

    def remove(self, servo: VirtualServo) -> None:
        """Disconnect a servo (and forget its faults)."""
        with self.lock:
            self.settle()
            self._servos.remove(servo)
            self.faults.clear(servo)

    def servos_with_id(self, servo_id: int) -> list[VirtualServo]:
        """Every servo whose ID register holds `servo_id`, stepped up to now."""
        with self.lock:
            self.settle()
            return [s for s in self._servos if s.servo_id == servo_id]

    def servo(self, servo_id: int) -> VirtualServo:
        """The (first) servo with `servo_id`; EmulationError naming the IDs present if none."""
        found = self.servos_with_id(servo_id)
        if not found:
            ids = sorted({s.servo_id for s in self._servos})
            raise EmulationError(f"no emulated servo with ID {servo_id}; IDs on the bus: {ids}")
        return found[0]

    @property
    def parser_stats(self) -> ParserStats:
        """What the Protocol 2.0 receiver dropped so far (garbage, bad CRCs, stale partial
        packets)."""
        return self._parser.stats

    @property
    def parser1_stats(self) -> ParserStats:
        """The same for the Protocol 1.0 receiver (`crc_errors` counts bad checksums)."""
        return self._parser1.stats

    # ------------------------------------------------------------------ time and traffic
    def advance(self, dt_s: float, *, bytes_waiting: bool = False) -> None:
        """Let `dt_s` seconds of bus time pass: `physics` (if any) now, the servos' own steps
        when their state is next needed (see the module docstring).

        `bytes_waiting`: host bytes that arrived at some unknown moment within `dt_s` are still
        unread (a transport that was starved of CPU); feed them next with `receive`. The Bus
        Watchdog then fires no earlier than the following advance, so the transport's own lost
        time is not charged to a host that kept writing.
        """
        if dt_s <= 0.0:
            return
        with self.lock:
            self.now_s += dt_s
            if self.physics is not None:
                self.physics.advance(self._servos, dt_s)
            self._unstepped_s += dt_s
            self._judge_watchdog = not bytes_waiting
            if self._unstepped_s >= SETTLE_AFTER_S:
                self._step_servos(math.floor(self._unstepped_s / STEP_S) * STEP_S)

    def settle(self) -> None:
        """Step every servo through the bus time that passed since its last step.

        The chain does this itself before it executes a packet and when its servos are looked
        up; call it before reading a servo held from earlier (its `state`, `peek`, ...).
        """
        with self.lock:
            self._step_servos(self._unstepped_s)

    def _step_servos(self, dt_s: float) -> None:
        if dt_s <= 0.0:
            return
        self._unstepped_s = max(0.0, self._unstepped_s - dt_s)
        judge = self._judge_watchdog
        for servo in self._servos:
            servo.step(dt_s, judge_watchdog=judge)

    def byte_time_s(self) -> float:
        """Seconds per byte at the line rate."""
        return byte_time_s(self.baud)

    def receive(self, data: bytes | bytearray, *, idle_s: float | None = None) -> list[BusReply]:
        """Take bytes the host sent (ending now) and return the replies, timed from now.

        Complete packets are executed in order; each later packet's replies follow the earlier
        ones. Garbage and damaged packets are dropped silently, as a servo's receiver does; a
        partial packet is dropped when the line was idle too long before `data` (`idle_s`, by
        default the bus time since the last bytes; a transport that cannot tell when bytes
        arrived passes the idle time it saw).
        """
        with self.lock:
            replies: list[BusReply] = []
            offset = 0.0
            speaks = {2.0 if s.speaks_protocol_2 else 1.0 for s in self._servos}
            # Each receiver sees every byte; one that no servo on the bus speaks is skipped (its
            # servos could only appear by an `add` or a Protocol Type write, which resets it).
            # Within one call, Protocol 2.0 packets are served before Protocol 1.0 ones: a host
            # waits for each reply, so one call rarely holds both. Each packet acts at now: the
            # servos are stepped up to it first.
            if 2.0 in speaks:
                for packet in self._parser.feed(data, self.now_s, idle_s=idle_s):
                    self.settle()
                    hearing = self._hearing(2.0)
                    timed = self._timed(instructions.execute(packet, hearing), offset)
                    replies += timed
                    offset = max([offset, *(r.end_s(self.baud) for r in timed)])
            else:
                self._parser.reset()
            if 1.0 in speaks:
                for packet1 in self._parser1.feed(data, self.now_s, idle_s=idle_s):
                    self.settle()
                    slots: list[Slot] = []
                    for vendor, hearing in _by_vendor(self._hearing(1.0)).items():
                        slots += _ONE_FRAMING[vendor](packet1, hearing)
                    timed = self._timed(slots, offset)
                    replies += timed
                    offset = max([offset, *(r.end_s(self.baud) for r in timed)])
            else:
                self._parser1.reset()
            return merge_collisions(replies, self.baud)

    def _hearing(self, version: float) -> list[VirtualServo]:
        """The servos that receive a packet of protocol `version` now."""
        return [
            s
            for s in self._servos
            if s.baud == self.baud
            and (2.0 if s.speaks_protocol_2 else 1.0) == version
            and self.faults.hears(s)
        ]

    def _timed(self, slots: list[Slot], offset: float) -> list[BusReply]:
        """Place each slot after the previous one; apply drop, corruption and delay faults."""
        cursor, per_byte = offset, self.byte_time_s()
        out: list[BusReply] = []
        for slot in slots:
            slot_end = cursor
            for servo, data in slot.replies:
                start = cursor + servo.processing_time_s + self.faults.delay_s(servo)
                start += 0.0 if slot.segment else servo.return_delay_s
                slot_end = max(slot_end, start + len(data) * per_byte)
                delivered = self.faults.filter_reply(servo, data)
                if delivered is not None:
                    out.append(BusReply(start, delivered))
            cursor = slot_end
        return out

    # ------------------------------------------------------------------ fault injection
    def _targets(self, target: Target) -> list[VirtualServo]:
        if isinstance(target, VirtualServo):
            self.settle()
            return [target]
        found = self.servos_with_id(target)
        if not found:
            self.servo(target)
        return found

    def silence(self, target: Target, silent: bool = True) -> None:
        """Take servos off the bus (they hear and answer nothing), or put them back; an axis of
        a multi-axis servo takes its whole case (one connector, one module)."""
        with self.lock:
            for servo in self._targets(target):
                axes = servo.case.axes if servo.case is not None else (servo,)
                for axis in axes:
                    self.faults.update(axis, silent=silent)

    def drop_replies(self, target: Target, *, next_n: int = 0, probability: float = 0.0) -> None:
        """Lose the next `next_n` replies, then each with `probability`; instructions still run."""
        with self.lock:
            for servo in self._targets(target):
                self.faults.update(servo, drop_next=next_n, drop_probability=probability)

    def corrupt_replies(self, target: Target, *, next_n: int = 0, probability: float = 0.0) -> None:
        """Flip one byte after the header in the next `next_n` replies, then with `probability`."""
        with self.lock:
            for servo in self._targets(target):
                self.faults.update(servo, corrupt_next=next_n, corrupt_probability=probability)

    def delay_replies(self, target: Target, delay_s: float) -> None:
        """Answer `delay_s` seconds late (beyond the SDK's ~34 ms timeout the reply is missed)."""
        with self.lock:
            for servo in self._targets(target):
                self.faults.update(servo, delay_s=delay_s)

    def latch_hardware_error(self, target: Target, bits: int = HardwareError.OVERLOAD) -> None:
        """Latch raw error bits as the model reports them (Hardware Error Status on an X, the
        status byte on a Feetech servo); `latch_fault` names the fault instead."""
        with self.lock:
            for servo in self._targets(target):
                servo.latch_error(bits)

    def latch_fault(self, target: Target, fault: Fault) -> None:
        """Latch `fault` as each servo's firmware reports it (its own bits: Dynamixel's Hardware
        Error Status, Feetech's status byte)."""
        with self.lock:
            for servo in self._targets(target):
                servo.latch_fault(fault)

    def faults_of(self, servo: VirtualServo) -> Faults:
        """The fault settings of one servo."""
        return self.faults.get(servo)

    def clear_faults(self, target: Target | None = None) -> None:
        """Remove injected bus faults (not latched hardware errors: those need a reboot)."""
        with self.lock:
            servos = self._servos if target is None else self._targets(target)
            for servo in servos:
                self.faults.clear(servo)


def make_chain_for_ids(
    model: str | int | ServoTable,
    ids: Iterable[int],
    baud: int = FACTORY_BAUD,
    *,
    motion: MotionModel | None = None,
    seed: int = 0,
) -> EmulatedChain:
    """A chain of identical servos with the given IDs, all configured for and listening at `baud`.

    `motion` is shared by every servo when given (an external physics bridge); otherwise each gets
    its own kinematic `ProfileMotion`. A multi-axis model (2XL430) pairs the IDs into cases in
    the order given (`cases_of`): EmulationError unless they fill whole cases.
    """
    table = model if isinstance(model, ServoTable) else table_for_model(model)
    servos = [VirtualServo(table, servo_id, baud=baud, motion=motion) for servo_id in ids]
    cases_of(servos)
    return EmulatedChain(servos, baud=baud, seed=seed)
