"""Soak the Dynamixel control loop in virtual time: hours of 200 Hz cycles, lost cycles, memory.

The real ServoChainBackend and runner drive snake12 (sidewinding) through the unmodified
dynamixel_sdk on the in-process emulator (``dxlemu://``, virtual time: the bus clock is the only
clock, so an hour of control takes as long as the CPU needs, and every lost cycle is the bus's,
not the host's). Reported: cycles run against cycles planned (lost cycles), overruns, retries,
Bus Watchdog trips, and memory: RSS (from /proc) sampled along the run with its growth after
warm-up, and, with ``--tracemalloc``, Python heap growth and its largest sources.

Usage: python tools/soak_virtual.py [--hours 1 | --cycles 720000] [--rate 200] [--tracemalloc]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import math
import time
import tracemalloc
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from snakebot.backends.chain import ServoChainBackend
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.emulation import make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.gaits import make_gait


def rss_bytes() -> int:
    """Resident set size of this process (Linux /proc; 0 elsewhere)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


@dataclass
class SoakResult:
    """What a soak measured; memory in bytes, samples as (cycle, bytes)."""

    cycles_planned: int
    cycles_run: int
    rate_hz: float
    virtual_s: float
    wall_s: float
    overruns: int
    retries: int
    group_retries: int
    watchdog_trips: int
    rss_samples: list[tuple[int, int]] = field(default_factory=list)
    heap_samples: list[tuple[int, int]] = field(default_factory=list)
    heap_top: list[str] = field(default_factory=list)

    @property
    def lost_cycles(self) -> int:
        """Cycles planned that did not run (the schedule slipped)."""
        return max(0, self.cycles_planned - self.cycles_run)

    @staticmethod
    def growth(samples: list[tuple[int, int]]) -> int:
        """Bytes gained from the first sample after warm-up (the second) to the last."""
        return samples[-1][1] - samples[1][1] if len(samples) > 2 else 0

    def report(self) -> dict[str, object]:
        """The figures as one JSON-ready dict."""
        return {
            "cycles_planned": self.cycles_planned,
            "cycles_run": self.cycles_run,
            "lost_cycles": self.lost_cycles,
            "rate_hz": self.rate_hz,
            "virtual_s": round(self.virtual_s, 3),
            "wall_s": round(self.wall_s, 1),
            "overruns": self.overruns,
            "retries": self.retries,
            "group_retries": self.group_retries,
            "watchdog_trips": self.watchdog_trips,
            "rss_start_mib": round(self.rss_samples[1][1] / 2**20, 2) if self.rss_samples else None,
            "rss_growth_kib": round(self.growth(self.rss_samples) / 1024, 1),
            "heap_growth_kib": round(self.growth(self.heap_samples) / 1024, 1),
            "heap_top": self.heap_top,
        }


def soak(
    cycles: int, rate_hz: float = 200.0, *, samples: int = 20, trace: bool = False
) -> SoakResult:
    """Run ``cycles`` control cycles at ``rate_hz`` in virtual time and measure them."""
    base = load_robot("snake12")
    robot = dataclasses.replace(base, safety=dataclasses.replace(base.safety, ramp_s=0.5))
    chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud=robot.bus.baud)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    every = max(1, cycles // samples)
    result = SoakResult(cycles, 0, rate_hz, 0.0, 0.0, 0, 0, 0, 0)
    if trace:
        tracemalloc.start()
    first: tracemalloc.Snapshot | None = None

    def sample(cycle: int, gait_time_s: float) -> None:
        nonlocal first
        result.cycles_run = cycle
        if cycle % every == 0:
            result.rss_samples.append((cycle, rss_bytes()))
            if trace:
                result.heap_samples.append((cycle, tracemalloc.get_traced_memory()[0]))
                if len(result.heap_samples) == 2:
                    first = tracemalloc.take_snapshot()

    started = time.perf_counter()
    with registered(chain) as url:
        backend = ServoChainBackend(
            robot,
            port=url,
            port_handler_factory=EmulatedPortHandler,
            clock=lambda: chain.now_s,
            sleep=chain.advance,
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with backend:
                start_s = chain.now_s
                run_gait(
                    backend,
                    make_gait("sidewinding", robot.joint_count),
                    SafetyLayer.for_robot(robot),
                    # Half a period past the last deadline: exactly `cycles` if none is lost.
                    RunPlan(duration_s=(cycles + 0.5) / rate_hz, rate_hz=rate_hz, ramp_out=False),
                    RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
                    on_cycle=sample,
                )
                result.virtual_s = chain.now_s - start_s
        result.overruns = backend.stats.overruns
        result.retries = sum(backend.bus.retry_counts.values())
        result.group_retries = backend.bus.group_retries
        result.watchdog_trips = int(backend.stats.extra.get("watchdog_trips", 0))
    result.wall_s = time.perf_counter() - started
    if trace and first is not None:
        stats = tracemalloc.take_snapshot().compare_to(first, "lineno")
        result.heap_top = [str(s) for s in stats[:5]]
        tracemalloc.stop()
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--hours", type=float, help="virtual hours of control (default 1)")
    group.add_argument("--cycles", type=int, help="control cycles (overrides --hours)")
    parser.add_argument("--rate", type=float, default=200.0, help="control rate in Hz")
    parser.add_argument(
        "--tracemalloc", action="store_true", help="also trace the Python heap (slower)"
    )
    args = parser.parse_args()
    cycles = args.cycles or math.ceil((args.hours or 1.0) * 3600 * args.rate)
    logging.getLogger("snakebot").setLevel(logging.ERROR)
    result = soak(cycles, args.rate, trace=args.tracemalloc)
    print(json.dumps(result.report(), indent=2))


if __name__ == "__main__":
    main()
