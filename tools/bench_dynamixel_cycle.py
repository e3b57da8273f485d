"""Control-cycle cost of DynamixelBackend against a bare dynamixel_sdk loop, on the emulator.

One cycle = one Sync Write of N goal positions + one Fast Sync Read of load, velocity and position
(126..135), decoded to SI. Both sides talk through the real SDK and ``EmulatedPortHandler`` to
identical in-process emulated chains (``dxlemu://``, virtual time: no wire time is waited, so this
measures host CPU per cycle). Within a round the two sides alternate cycle by cycle; each round
gives a median per side and their ratio; the table reports medians over rounds (sizes shuffled).
The wire-time limit is the bus time of the same cycle at 1, 3 and 4 Mbps with return delay 0
(10 bits per byte).

Usage: python tools/bench_dynamixel_cycle.py [--rounds 9] [--cycles 300] [--sizes 8 16 32]
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

from snakebot.backends.dynamixel.backend import DynamixelBackend
from snakebot.backends.dynamixel.checks import cycle_wire_time_s
from snakebot.config import load_robot
from snakebot.config.schema import RobotConfig
from snakebot.emulation import EmulatedChain, make_chain_for_ids, register_chain
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.types import JointCommand

MODEL = "XL430-W250"
BAUD = 1_000_000
READ_ADDRESS, READ_LENGTH, GOAL_ADDRESS = 126, 10, 116
RAD_PER_TICK = 2 * math.pi / 4096
RAD_S_PER_UNIT = 0.229 * 2 * math.pi / 60
NM_PER_LOAD_UNIT = 0.001 * 1.4


def robot_for(n: int) -> RobotConfig:
    robot = load_robot("snake8")
    joints = tuple(dataclasses.replace(robot.joints[0], servo_id=i + 1) for i in range(n))
    safety = dataclasses.replace(robot.safety, ramp_s=0.0)
    return dataclasses.replace(robot, joints=joints, safety=safety)


def chain_for(n: int) -> EmulatedChain:
    chain = make_chain_for_ids(MODEL, range(1, n + 1), baud=BAUD)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    return chain


def signed(value: int, bits: int) -> int:
    return value - (1 << bits) if value >> (bits - 1) else value


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
            self.writer.changeParam(servo_id, [
                sdk.DXL_LOBYTE(sdk.DXL_LOWORD(ticks)), sdk.DXL_HIBYTE(sdk.DXL_LOWORD(ticks)),
                sdk.DXL_LOBYTE(sdk.DXL_HIWORD(ticks)), sdk.DXL_HIBYTE(sdk.DXL_HIWORD(ticks)),
            ])
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


def make_sides(n: int, cycles: int) -> dict[str, Side]:
    handlers: list[EmulatedPortHandler] = []

    def factory(name: str) -> EmulatedPortHandler:
        handlers.append(EmulatedPortHandler(name))
        return handlers[-1]

    chain = chain_for(n)
    # The chain's virtual clock, as the servos see it (the Bus Watchdog check runs on it too);
    # slow_every off: only the cycle's two transactions.
    backend = DynamixelBackend(robot_for(n), port=register_chain(chain), baud=BAUD,
                               port_handler_factory=factory, slow_every=10**9,
                               clock=lambda: chain.now_s, sleep=chain.advance)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        backend.connect()
    bare = BareLoop(register_chain(chain_for(n)), n)
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=9)
    parser.add_argument("--cycles", type=int, default=300)
    parser.add_argument("--sizes", type=int, nargs="+", default=[8, 16, 32])
    args = parser.parse_args()

    setups = {n: make_sides(n, args.cycles) for n in args.sizes}
    for sides in setups.values():  # warm-up
        measure_round(sides, 30)
    results: dict[int, dict[str, list[float]]] = {n: {} for n in args.sizes}
    rng = random.Random(7)
    for _ in range(args.rounds):
        order = list(args.sizes)
        rng.shuffle(order)
        for n in order:
            got = measure_round(setups[n], args.cycles)
            row = results[n]
            for name, (whole, client) in got.items():
                row.setdefault(f"{name}_whole", []).append(whole)
                row.setdefault(f"{name}_client", []).append(client)
            for index, part in enumerate(("whole", "client")):
                ratio = got["backend"][index] / got["bare"][index]
                row.setdefault(f"ratio_{part}", []).append(ratio)

    print(f"Python {platform.python_version()}, {os.cpu_count()} CPUs, {args.rounds} rounds x "
          f"{args.cycles} cycles per side, {MODEL}, Sync Write + Fast Sync Read of 10 B.")
    print("µs per cycle, medians over rounds; 'client' excludes the time spent inside the "
          "emulated port (the emulator's own work).\n")
    print("| N | bare SDK loop: cycle (client) | DynamixelBackend: cycle (client) "
          "| ratio cycle | ratio client (min–max) | wire limit 1 / 3 / 4 Mbps, RDT 0 |")
    print("|---|---|---|---|---|---|")

    def med(values: list[float], scale: float = 1e6) -> float:
        return statistics.median(values) * scale

    for n in args.sizes:
        r = results[n]
        wire = [cycle_wire_time_s(n, READ_LENGTH, b, fast=True) * 1e6
                for b in (1_000_000, 3_000_000, 4_000_000)]
        print(f"| {n} | {med(r['bare_whole']):.0f} ({med(r['bare_client']):.0f}) "
              f"| {med(r['backend_whole']):.0f} ({med(r['backend_client']):.0f}) "
              f"| {med(r['ratio_whole'], 1):.2f} "
              f"| {med(r['ratio_client'], 1):.2f} ({min(r['ratio_client']):.2f}–"
              f"{max(r['ratio_client']):.2f}) "
              f"| {wire[0]:.0f} / {wire[1]:.0f} / {wire[2]:.0f} |")

if __name__ == "__main__":
    main()
