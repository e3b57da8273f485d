"""Control-cycle cost of ServoChainBackend against a bare dynamixel_sdk loop, per servo family.

One cycle = one Sync Write of N goal positions + one state read (load, velocity, position)
decoded to SI, by the family's read method: X-series (XL430-W250, Protocol 2.0) one Fast Sync
Read of 126..135; MX-28 (Protocol 1.0 firmware) one Bulk Read of 36..41; AX-12A (Protocol 1.0, no
group read) one Read of 36..41 per servo. Both sides talk through the real SDK and
``EmulatedPortHandler`` to identical in-process emulated chains (``dxlemu://``, virtual time: no
wire time is waited, so this measures host CPU per cycle). Within a round the two sides alternate
cycle by cycle; each round gives a median per side and their ratio; the table reports medians over
rounds (sizes shuffled).

``--sizes`` (X only, the historical table): the wire-time limit of the same cycle at 1, 3 and
4 Mbps with return delay 0 (10 bits per byte). ``--families``: 12 servos of each family at
1 Mbps, with the control rate the bus holds at Return Delay Time 0 and 250 (500 µs): wire time,
one Return Delay per reply turnaround, 1 ms of USB latency per reply wait (an FTDI adapter at
latency_timer 1; snakebot.backends.chain.rate) plus the backend's host CPU.

Usage: python tools/bench_dynamixel_cycle.py [--rounds 9] [--cycles 300] [--sizes 8 16 32]
       python tools/bench_dynamixel_cycle.py --families [--rounds 9] [--cycles 300]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import platform
import random
import statistics
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import dynamixel_sdk as sdk
import numpy as np

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.backends.chain.blocks import resolve_block
from snakebot.backends.chain.checks import cycle_wire_time_s
from snakebot.backends.chain.rate import METHOD_NAMES, cycle_budget
from snakebot.config import load_robot
from snakebot.config.loader import load_servo_model
from snakebot.config.schema import RobotConfig
from snakebot.emulation import EmulatedChain, make_chain_for_ids, register_chain
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.families import family_for, family_named
from snakebot.servo_tables import table_for_model
from snakebot.types import JointCommand

MODEL = "XL430-W250"
BAUD = 1_000_000
READ_ADDRESS, READ_LENGTH, GOAL_ADDRESS = 126, 10, 116
RAD_PER_TICK = 2 * math.pi / 4096
RAD_S_PER_UNIT = 0.229 * 2 * math.pi / 60
NM_PER_LOAD_UNIT = 0.001 * 1.4
P1_READ_ADDRESS, P1_READ_LENGTH, P1_GOAL_ADDRESS = 36, 6, 30  # AX/MX: position, speed, load


@dataclass(frozen=True)
class Kind:
    """One family's benchmark: model, protocol, how the state is read, and the bare loop."""

    name: str
    model: str
    protocol: float
    method: str
    robot: str  # the shipped robot whose joints and safety the bench's robot starts from
    ticks: int  # per turn
    travel_rad: float
    speed_unit_rad_s: float


KINDS = {
    "x": Kind(
        "X-series (XL430-W250), Protocol 2.0",
        MODEL,
        2.0,
        "fast_sync_read",
        "snake8",
        4096,
        2 * math.pi,
        RAD_S_PER_UNIT,
    ),
    "mx": Kind(
        "MX-28, Protocol 1.0",
        "MX-28",
        1.0,
        "bulk_read",
        "snake12-ax12a",
        4096,
        2 * math.pi,
        0.114 * 2 * math.pi / 60,
    ),
    "ax": Kind(
        "AX-12A, Protocol 1.0",
        "AX-12A",
        1.0,
        "read",
        "snake12-ax12a",
        1024,
        math.radians(300),
        0.111 * 2 * math.pi / 60,
    ),
}


def robot_for(n: int, kind: Kind | None = None) -> RobotConfig:
    """n joints of the kind's servos, IDs 1..n, no ramp."""
    kind = kind or KINDS["x"]
    base = load_robot(kind.robot)
    if kind.model != base.servo.name:
        base = dataclasses.replace(base, servo=load_servo_model(kind.model, base.source))
    joints = tuple(dataclasses.replace(base.joints[0], servo_id=i + 1) for i in range(n))
    safety = dataclasses.replace(base.safety, ramp_s=0.0)
    return dataclasses.replace(base, joints=joints, safety=safety)


def chain_for(n: int, kind: Kind | None = None) -> EmulatedChain:
    chain = make_chain_for_ids((kind or KINDS["x"]).model, range(1, n + 1), baud=BAUD)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    return chain


def signed(value: int, bits: int) -> int:
    return value - (1 << bits) if value >> (bits - 1) else value


def magnitude(value: int) -> int:
    """Protocol 1.0 Present Speed/Load: bit 10 the sign, bits 0-9 the size."""
    return -(value & 0x3FF) if value & 0x400 else value & 0x3FF


class BareLoop:
    """What a careful user writes with dynamixel_sdk: groups built once, getData decoding."""

    def __init__(self, url: str, n: int) -> None:
        self.ids = list(range(1, n + 1))
        self.port = EmulatedPortHandler(url)
        self.port.setBaudRate(BAUD)
        self.packet = sdk.PacketHandler(2.0)
        self.writer = sdk.GroupSyncWrite(self.port, self.packet, GOAL_ADDRESS, 4)
        self.reader = sdk.GroupSyncRead(self.port, self.packet, READ_ADDRESS, READ_LENGTH)
        for servo_id in self.ids:
            self.writer.addParam(servo_id, [0, 8, 0, 0])
            self.reader.addParam(servo_id)
            self.packet.write1ByteTxRx(self.port, servo_id, 64, 1)

    def cycle(self, goal_rad: list[float]) -> tuple[list[float], list[float], list[float]]:
        for servo_id, angle in zip(self.ids, goal_rad, strict=True):
            ticks = round(2048 + angle / RAD_PER_TICK)
            self.writer.changeParam(
                servo_id,
                [
                    sdk.DXL_LOBYTE(sdk.DXL_LOWORD(ticks)),
                    sdk.DXL_HIBYTE(sdk.DXL_LOWORD(ticks)),
                    sdk.DXL_LOBYTE(sdk.DXL_HIWORD(ticks)),
                    sdk.DXL_HIBYTE(sdk.DXL_HIWORD(ticks)),
                ],
            )
        if self.writer.txPacket() != sdk.COMM_SUCCESS:
            raise RuntimeError("sync write failed")
        if self.reader.fastSyncRead() != sdk.COMM_SUCCESS:
            raise RuntimeError("fast sync read failed")
        position, velocity, effort = [], [], []
        for servo_id in self.ids:
            pos = signed(self.reader.getData(servo_id, 132, 4), 32)
            vel = signed(self.reader.getData(servo_id, 128, 4), 32)
            load = signed(self.reader.getData(servo_id, 126, 2), 16)
            position.append((pos - 2048) * RAD_PER_TICK)
            velocity.append(vel * RAD_S_PER_UNIT)
            effort.append(load * NM_PER_LOAD_UNIT)
        return position, velocity, effort


class BareLoopP1:
    """The same for Protocol 1.0: Sync Write of 2-byte goals, then a Bulk Read (MX) or one
    readTxRx per servo (AX). The SDK 4.1 GroupBulkRead cannot send a P1 request (it passes
    P2's fast_option), so the careful user sends it with the handler's own bulkReadTx."""

    def __init__(self, url: str, n: int, kind: Kind) -> None:
        self.ids = list(range(1, n + 1))
        self.kind = kind
        self.centre = kind.ticks // 2
        self.rad_per_tick = kind.travel_rad / kind.ticks
        self.port = EmulatedPortHandler(url)
        self.port.setBaudRate(BAUD)
        self.packet = sdk.PacketHandler(1.0)
        self.writer = sdk.GroupSyncWrite(self.port, self.packet, P1_GOAL_ADDRESS, 2)
        self.bulk = sdk.GroupBulkRead(self.port, self.packet)
        for servo_id in self.ids:
            self.writer.addParam(servo_id, [0, 2])
            self.bulk.addParam(servo_id, P1_READ_ADDRESS, P1_READ_LENGTH)
            self.packet.write1ByteTxRx(self.port, servo_id, 24, 1)
        self.bulk.makeParam()

    def cycle(self, goal_rad: list[float]) -> tuple[list[float], list[float], list[float]]:
        for servo_id, angle in zip(self.ids, goal_rad, strict=True):
            ticks = round(self.centre + angle / self.rad_per_tick)
            self.writer.changeParam(servo_id, [sdk.DXL_LOBYTE(ticks), sdk.DXL_HIBYTE(ticks)])
        if self.writer.txPacket() != sdk.COMM_SUCCESS:
            raise RuntimeError("sync write failed")
        rows = []
        if self.kind.method == "bulk_read":
            param = self.bulk.param
            if self.packet.bulkReadTx(self.port, param, len(param)) != sdk.COMM_SUCCESS:
                raise RuntimeError("bulk read failed")
            if self.bulk.rxPacket() != sdk.COMM_SUCCESS:
                raise RuntimeError("bulk read failed")
            for servo_id in self.ids:
                rows.append(
                    (
                        self.bulk.getData(servo_id, 36, 2),
                        self.bulk.getData(servo_id, 38, 2),
                        self.bulk.getData(servo_id, 40, 2),
                    )
                )
        else:
            for servo_id in self.ids:
                data, result, _ = self.packet.readTxRx(
                    self.port, servo_id, P1_READ_ADDRESS, P1_READ_LENGTH
                )
                if result != sdk.COMM_SUCCESS:
                    raise RuntimeError("read failed")
                rows.append(
                    (data[0] | data[1] << 8, data[2] | data[3] << 8, data[4] | data[5] << 8)
                )
        position, velocity, effort = [], [], []
        for pos, vel, load in rows:
            position.append((pos - self.centre) * self.rad_per_tick)
            velocity.append(magnitude(vel) * self.kind.speed_unit_rad_s)
            effort.append(magnitude(load) * NM_PER_LOAD_UNIT)
        return position, velocity, effort


class EmulatorClock:
    """Accumulates the seconds spent inside the emulated serial port (the emulator's own work)."""

    def __init__(self) -> None:
        self.seconds = 0.0

    def instrument(self, port: EmulatedPortHandler) -> None:
        serial_port = port.ser
        for name in ("read", "write", "reset_input_buffer"):
            setattr(serial_port, name, self._timed(getattr(serial_port, name)))

    def _timed(self, method: Callable[..., Any]) -> Callable[..., Any]:
        def timed(*args: Any) -> Any:
            start = time.perf_counter()
            try:
                return method(*args)
            finally:
                self.seconds += time.perf_counter() - start

        return timed


@dataclass
class Side:
    """One side of the comparison: a cycle function, its goals and its emulator clock."""

    run: Callable[[Any], object]
    goals: list[Any]
    emulator: EmulatorClock

    def cycle(self, index: int) -> tuple[float, float]:
        """Seconds of one cycle: (whole cycle, client side = whole minus time in the emulator)."""
        inside = self.emulator.seconds
        start = time.perf_counter()
        self.run(self.goals[index % len(self.goals)])
        elapsed = time.perf_counter() - start
        return elapsed, elapsed - (self.emulator.seconds - inside)


def measure_round(sides: dict[str, Side], cycles: int) -> dict[str, tuple[float, float]]:
    """Cycle by cycle alternation (which side goes first alternates too), so both sides see the
    same machine load and equally cold caches; medians per side of (whole, client)."""
    samples: dict[str, list[tuple[float, float]]] = {name: [] for name in sides}
    names = list(sides)
    for k in range(cycles):
        for name in names if k % 2 else reversed(names):
            samples[name].append(sides[name].cycle(k))
    return {
        name: (statistics.median(s[0] for s in got), statistics.median(s[1] for s in got))
        for name, got in samples.items()
    }


def make_sides(n: int, cycles: int, kind: Kind | None = None) -> dict[str, Side]:
    kind = kind or KINDS["x"]
    handlers: list[EmulatedPortHandler] = []

    def factory(name: str) -> EmulatedPortHandler:
        handlers.append(EmulatedPortHandler(name))
        return handlers[-1]

    chain = chain_for(n, kind)
    # The chain's virtual clock, as the servos see it (the Bus Watchdog check runs on it too);
    # slow_every off: only the cycle's two transactions.
    backend = ServoChainBackend(
        robot_for(n, kind),
        port=register_chain(chain),
        baud=BAUD,
        port_handler_factory=factory,
        slow_every=10**9,
        clock=lambda: chain.now_s,
        sleep=chain.advance,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        backend.connect()
    assert backend.bus.capabilities.read_method == kind.method
    url = register_chain(chain_for(n, kind))
    bare: BareLoop | BareLoopP1 = (
        BareLoop(url, n) if kind.method == "fast_sync_read" else BareLoopP1(url, n, kind)
    )
    clocks = {"backend": EmulatorClock(), "bare": EmulatorClock()}
    clocks["backend"].instrument(handlers[0])
    clocks["bare"].instrument(bare.port)
    t = np.arange(cycles) * 0.005
    waves = [0.5 * np.sin(2 * math.pi * 1.0 * tk - 0.6 * np.arange(n)) for tk in t]

    def run_backend(command: JointCommand) -> None:
        backend.send_command(command)
        backend.read_state()

    return {  # each side gets its input precomputed in its natural form
        "backend": Side(run_backend, [JointCommand(w) for w in waves], clocks["backend"]),
        "bare": Side(bare.cycle, [w.tolist() for w in waves], clocks["bare"]),
    }


def measure(
    setups: dict[Any, dict[str, Side]],
    rounds: int,
    cycles: int,
) -> dict[Any, dict[str, list[float]]]:
    """Rounds of every setup in shuffled order: per setup, each side's whole and client medians
    per round and the backend/bare ratios."""
    for sides in setups.values():  # warm-up
        measure_round(sides, 30)
    results: dict[Any, dict[str, list[float]]] = {key: {} for key in setups}
    rng = random.Random(7)
    for _ in range(rounds):
        order = list(setups)
        rng.shuffle(order)
        for key in order:
            got = measure_round(setups[key], cycles)
            row = results[key]
            for name, (whole, client) in got.items():
                row.setdefault(f"{name}_whole", []).append(whole)
                row.setdefault(f"{name}_client", []).append(client)
            for index, part in enumerate(("whole", "client")):
                ratio = got["backend"][index] / got["bare"][index]
                row.setdefault(f"ratio_{part}", []).append(ratio)
    return results


def med(values: list[float], scale: float = 1e6) -> float:
    return statistics.median(values) * scale


def sizes_table(args: argparse.Namespace) -> None:
    setups = {n: make_sides(n, args.cycles) for n in args.sizes}
    results = measure(setups, args.rounds, args.cycles)
    print(
        f"Python {platform.python_version()}, {os.cpu_count()} CPUs, {args.rounds} rounds x "
        f"{args.cycles} cycles per side, {MODEL}, Sync Write + Fast Sync Read of 10 B."
    )
    print(
        "µs per cycle, medians over rounds; 'client' excludes the time spent inside the "
        "emulated port (the emulator's own work).\n"
    )
    print(
        "| N | bare SDK loop: cycle (client) | ServoChainBackend: cycle (client) "
        "| ratio cycle | ratio client (min–max) | wire limit 1 / 3 / 4 Mbps, RDT 0 |"
    )
    print("|---|---|---|---|---|---|")
    family = family_named("dynamixel-p2")
    for n in args.sizes:
        r = results[n]
        wire = [
            cycle_wire_time_s(family, "fast_sync_read", n, READ_LENGTH, b)[0] * 1e6
            for b in (1_000_000, 3_000_000, 4_000_000)
        ]
        print(
            f"| {n} | {med(r['bare_whole']):.0f} ({med(r['bare_client']):.0f}) "
            f"| {med(r['backend_whole']):.0f} ({med(r['backend_client']):.0f}) "
            f"| {med(r['ratio_whole'], 1):.2f} "
            f"| {med(r['ratio_client'], 1):.2f} ({min(r['ratio_client']):.2f}–"
            f"{max(r['ratio_client']):.2f}) "
            f"| {wire[0]:.0f} / {wire[1]:.0f} / {wire[2]:.0f} |"
        )


def families_table(args: argparse.Namespace) -> None:
    n = 12
    setups = {key: make_sides(n, args.cycles, kind) for key, kind in KINDS.items()}
    results = measure(setups, args.rounds, args.cycles)
    print(
        f"Python {platform.python_version()}, {os.cpu_count()} CPUs, {args.rounds} rounds x "
        f"{args.cycles} cycles per side, {n} servos at {BAUD} bit/s."
    )
    print(
        "Host CPU in µs per cycle ('client': the cycle minus the time inside the emulated "
        "port), medians over rounds; rates: wire + Return Delay per reply turnaround + 1 ms USB "
        "latency per reply wait + the backend's host CPU.\n"
    )
    print(
        "| family | read | bare SDK loop, client µs | ServoChainBackend, client µs "
        "| ratio client (min–max) | wire µs, RDT 0 | rate at RDT 0 | rate at RDT 250 (500 µs) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for key, kind in KINDS.items():
        r = results[key]
        table = table_for_model(kind.model)
        family = family_for(table, kind.protocol)
        read = resolve_block(table, ("present_position", "present_velocity", "present_load")).size
        write = table["goal_position"].size
        host_s = med(r["backend_client"], 1)
        rates = []
        for delay_s in (0.0, 500e-6):
            budget = cycle_budget(family, kind.method, n, read, write, BAUD, delay_s)
            rates.append(1.0 / (budget.cycle_s + host_s))
        wire = cycle_budget(family, kind.method, n, read, write, BAUD, 0.0).wire_s
        print(
            f"| {kind.name} | {METHOD_NAMES[kind.method]} "
            f"| {med(r['bare_client']):.0f} | {med(r['backend_client']):.0f} "
            f"| {med(r['ratio_client'], 1):.2f} ({min(r['ratio_client']):.2f}–"
            f"{max(r['ratio_client']):.2f}) | {wire * 1e6:.0f} "
            f"| {rates[0]:.0f} Hz | {rates[1]:.0f} Hz |"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=9)
    parser.add_argument("--cycles", type=int, default=300)
    parser.add_argument("--sizes", type=int, nargs="+", default=[8, 16, 32])
    parser.add_argument(
        "--families",
        action="store_true",
        help="12 servos of each family (X, MX, AX) instead of X at --sizes",
    )
    args = parser.parse_args()
    if args.families:
        families_table(args)
    else:
        sizes_table(args)


if __name__ == "__main__":
    main()
