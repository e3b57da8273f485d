"""Benchmark: what the twin's physics checks (docs/physics.md) cost a `snakebot run`.

Each round runs, back to back in shuffled order, the path of `snakebot run --backend sim`
(gait -> safety -> TwinBackend, metrics; no log) with the checks on (the default) and off
(`TwinBackend(health=None)`), for 8 and 16 servos. Ratios within a round, median over rounds.

    python tools/bench_health.py [--rounds 7] [--seconds 5]
"""

from __future__ import annotations

import argparse
import dataclasses
import random
import statistics
import time

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.health import DEFAULT_LIMITS, HealthLimits
from snakebot.config import RobotConfig, load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait

RATE_HZ = 100.0


def robot_with(joints: int) -> RobotConfig:
    """snake8 with ``joints`` servos (as tools/bench_twin.py builds them)."""
    base = load_robot("snake8")
    chain = tuple(dataclasses.replace(base.joints[0], servo_id=i + 1) for i in range(joints))
    return dataclasses.replace(base, joints=chain)


def steps_per_s(robot: RobotConfig, seconds: float, health: HealthLimits | None) -> float:
    """Simulated physics steps per wall-clock second of one run."""
    backend = TwinBackend(robot, health=health)
    gait = make_gait("serpenoid", robot.joint_count)
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    plan = RunPlan(duration_s=seconds, rate_hz=RATE_HZ, ramp_out=False)
    with backend:
        start = time.perf_counter()
        run_gait(backend, gait, SafetyLayer.for_robot(robot), plan, metrics)
        wall = time.perf_counter() - start
        steps = round(seconds / backend.model.opt.timestep)
    return steps / wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--seconds", type=float, default=5.0)
    args = parser.parse_args()
    print("| servos | checks on, steps/s | checks off, steps/s | on / off (min-max) |")
    print("|---|---|---|---|")
    for n in (8, 16):
        robot = robot_with(n)
        on, off, ratio = [], [], []
        for _ in range(args.rounds):
            got = {}
            for variant in random.sample(["on", "off"], 2):
                limits = DEFAULT_LIMITS if variant == "on" else None
                got[variant] = steps_per_s(robot, args.seconds, limits)
            on.append(got["on"])
            off.append(got["off"])
            ratio.append(got["on"] / got["off"])
        print(
            f"| {n} | {statistics.median(on):,.0f} | {statistics.median(off):,.0f} | "
            f"{statistics.median(ratio):.2f} ({min(ratio):.2f}-{max(ratio):.2f}) |"
        )


if __name__ == "__main__":
    main()
