"""The emulator's own cost per control cycle, against the cycle's wire time.

One cycle = one Sync Write of N goal positions (4 B) + one Fast Sync Read of Present Current,
Velocity and Position (126..135), sent by the stock SDK (`GroupSyncWrite`, `GroupSyncRead`) through
`EmulatedPortHandler` to an in-process chain of XL430-W250 at 4 Mbps, return delay 0, virtual time.
"emulator" is the CPU time (this thread's, so other processes' load does not count) spent inside
the emulated serial port: the chain's work (parsing, control tables, motion models, replies);
"motion steps" counts each servo's motion-model steps per cycle.
The goals follow a travelling sine, so every servo is moving. Medians over rounds.

Usage: python tools/bench_emulator.py [--rounds 7] [--cycles 200] [--sizes 8 16 32]
       [--baseline CHECKOUT]   # e.g. git worktree add /tmp/before <commit>: both, side by side
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import dynamixel_sdk as sdk

from snakebot.emulation import VirtualServo, make_chain_for_ids, register_chain
from snakebot.emulation.motion import ProfileMotion
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.families import family_for
from snakebot.servo_tables import table_for_model

MODEL = "XL430-W250"
BAUD = 4_000_000
READ_ADDRESS, READ_LENGTH, GOAL_ADDRESS = 126, 10, 116
RAD_PER_TICK = 2 * math.pi / 4096


class CountingMotion(ProfileMotion):
    """The stock kinematic model, counting its steps."""

    def __init__(self) -> None:
        super().__init__()
        self.steps = 0

    def step(self, servo: VirtualServo, dt_s: float) -> None:
        """Count, then step as `ProfileMotion` does."""
        self.steps += 1
        super().step(servo, dt_s)


class Rig:
    """N servos on one chain and the SDK groups a careful user builds once."""

    def __init__(self, n: int) -> None:
        chain = make_chain_for_ids(MODEL, range(1, n + 1), baud=BAUD)
        self.motions = []
        for servo in chain.servos:
            servo.motion = CountingMotion()
            self.motions.append(servo.motion)
            servo.poke("return_delay_time", 0)
            servo.poke("torque_enable", 1)
        self.n = n
        self.port = EmulatedPortHandler(register_chain(chain))
        self.port.setBaudRate(BAUD)
        self.packet = sdk.PacketHandler(2.0)
        self.writer = sdk.GroupSyncWrite(self.port, self.packet, GOAL_ADDRESS, 4)
        self.reader = sdk.GroupSyncRead(self.port, self.packet, READ_ADDRESS, READ_LENGTH)
        for servo_id in range(1, n + 1):
            self.writer.addParam(servo_id, [0, 8, 0, 0])
            self.reader.addParam(servo_id)
        self.inside_s = 0.0
        serial_port = self.port.ser
        for name in ("read", "write", "reset_input_buffer"):
            setattr(serial_port, name, self._timed(getattr(serial_port, name)))
        self.k = 0

    def _timed(self, method: Callable[..., Any]) -> Callable[..., Any]:
        def timed(*args: Any) -> Any:
            start = time.thread_time()
            try:
                return method(*args)
            finally:
                self.inside_s += time.thread_time() - start

        return timed

    def cycle(self) -> tuple[float, float]:
        """One cycle: (seconds inside the emulator, motion steps per servo)."""
        self.k += 1
        inside, steps = self.inside_s, sum(m.steps for m in self.motions)
        for servo_id in range(1, self.n + 1):
            angle = 0.5 * math.sin(2 * math.pi * 0.005 * self.k - 0.6 * servo_id)
            ticks = round(2048 + angle / RAD_PER_TICK)
            self.writer.changeParam(servo_id, list(ticks.to_bytes(4, "little")))
        if self.writer.txPacket() != sdk.COMM_SUCCESS:
            raise RuntimeError("sync write failed")
        if self.reader.fastSyncRead() != sdk.COMM_SUCCESS:
            raise RuntimeError("fast sync read failed")
        counted = sum(m.steps for m in self.motions) - steps
        return self.inside_s - inside, counted / self.n


def wire_time_s(n: int) -> float:
    """Bus time of the same cycle at `BAUD`, return delay 0 (10 bits per byte)."""
    family = family_for(table_for_model(MODEL))
    read = family.read_cost("fast_sync_read", n, READ_LENGTH)
    return (family.sync_write_bytes(n, 4) + read.wire_bytes) * 10.0 / BAUD


def measure(sizes: list[int], rounds: int, cycles: int) -> dict[int, tuple[list[float], float]]:
    """Per size: the median emulator seconds per cycle of each round, and the motion steps per
    servo per cycle."""
    rigs = {n: Rig(n) for n in sizes}
    for rig in rigs.values():  # warm-up
        for _ in range(20):
            rig.cycle()
    medians: dict[int, list[float]] = {n: [] for n in sizes}
    steps: dict[int, float] = {}
    for _ in range(rounds):
        for n, rig in rigs.items():
            got = [rig.cycle() for _ in range(cycles)]
            medians[n].append(statistics.median(s for s, _ in got))
            steps[n] = statistics.median(c for _, c in got)
    return {n: (medians[n], steps[n]) for n in sizes}


def baseline_round(checkout: Path, sizes: list[int], cycles: int) -> dict[int, tuple[float, float]]:
    """One round of the same measurement on another checkout's emulator (a subprocess with that
    checkout first on the path): per size (median seconds per cycle, steps per servo)."""
    command = [
        sys.executable,
        __file__,
        "--json",
        "--rounds",
        "1",
        "--cycles",
        str(cycles),
        "--sizes",
        *map(str, sizes),
    ]
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    out = subprocess.run(command, env=env, check=True, capture_output=True, text=True).stdout
    return {int(n): (v[0][0], v[1]) for n, v in json.loads(out).items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--cycles", type=int, default=200)
    parser.add_argument("--sizes", type=int, nargs="+", default=[8, 16, 32])
    parser.add_argument(
        "--baseline",
        type=Path,
        metavar="CHECKOUT",
        help="also measure the emulator of another checkout (e.g. a worktree of "
        "the commit before), round by round in alternation, side by side",
    )
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()

    if args.baseline is not None and not (args.baseline / "snakebot").is_dir():
        parser.error(f"--baseline {args.baseline}: not a snakebot checkout (no snakebot/ in it)")
    if args.json:
        print(json.dumps(measure(args.sizes, args.rounds, args.cycles)))
        return
    here: dict[int, list[float]] = {n: [] for n in args.sizes}
    there: dict[int, list[float]] = {n: [] for n in args.sizes}
    steps: dict[int, tuple[float, float]] = {}
    for k in range(args.rounds):
        # Which side goes first alternates, so both see the same machine load.
        for side in ("here", "there") if k % 2 else ("there", "here"):
            if side == "here":
                for n, (got, count) in measure(args.sizes, 1, args.cycles).items():
                    here[n] += got
                    steps[n] = (count, steps.get(n, (0.0, 0.0))[1])
            elif args.baseline is not None:
                for n, (seconds, count) in baseline_round(
                    args.baseline, args.sizes, args.cycles
                ).items():
                    there[n].append(seconds)
                    steps[n] = (steps.get(n, (0.0, 0.0))[0], count)

    print(
        f"Python {platform.python_version()}, {os.cpu_count()} CPUs, load "
        f"{os.getloadavg()[0]:.1f}, {args.rounds} rounds x {args.cycles} cycles, {MODEL} at "
        f"{BAUD // 1_000_000} Mbps, Sync Write + Fast Sync Read of {READ_LENGTH} B.\n"
    )

    def cell(values: list[float]) -> str:
        mid = statistics.median(values) * 1e6
        return f"{mid:.0f} ({min(values) * 1e6:.0f}–{max(values) * 1e6:.0f})"

    if args.baseline is None:
        print(
            "| N | emulator CPU per cycle, µs (min–max over rounds) "
            "| motion steps per servo per cycle | wire time, µs | emulator / wire |"
        )
        print("|---|---|---|---|---|")
    else:
        print(f"baseline: {args.baseline}\n")
        print(
            "| N | baseline: emulator CPU per cycle, µs | steps per servo per cycle "
            "| this checkout: emulator CPU per cycle, µs | steps per servo per cycle "
            "| wire time, µs | this checkout / wire |"
        )
        print("|---|---|---|---|---|---|---|")
    for n in args.sizes:
        wire = wire_time_s(n) * 1e6
        ratio = statistics.median(here[n]) * 1e6 / wire
        if args.baseline is None:
            print(f"| {n} | {cell(here[n])} | {steps[n][0]:.0f} | {wire:.0f} | {ratio:.2f} |")
        else:
            print(
                f"| {n} | {cell(there[n])} | {steps[n][1]:.0f} | {cell(here[n])} "
                f"| {steps[n][0]:.0f} | {wire:.0f} | {ratio:.2f} |"
            )


if __name__ == "__main__":
    main()
