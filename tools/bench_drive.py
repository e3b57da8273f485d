"""Benchmark: what driving live costs per control cycle, beside playing a gait by time.

For snake8 and snake12, each round times, back to back and in shuffled order, N cycles of:
  gait          gait.command(t) -> safety.filter            (the runner's gait step)
  live          LiveGait.command(t) -> safety.filter        (integrated phases, governor)
  live+status   the same plus LiveGait.status() and a DriveCycle, as the drive loop builds them
  display       DriveDisplay's per-cycle accounting, frames handed to its writer (a null stream)
Medians of microseconds per cycle over the rounds, and live / gait within each round.

    python tools/bench_drive.py [--rounds 7] [--cycles 2000]
"""

from __future__ import annotations

import argparse
import io
import random
import statistics
import time
from collections.abc import Callable

import numpy as np

from snakebot.config import RobotConfig, load_robot
from snakebot.control.safety import SafetyLayer
from snakebot.drive.display import DriveDisplay
from snakebot.drive.run import DriveCycle
from snakebot.gaits import LiveControls, LiveGait, make_gait
from snakebot.types import JointState

DT = 0.01
GAIT = {"snake8": "serpenoid", "snake12": "sidewinding"}


def drive_cycle(
    k: int, target: np.ndarray, command: np.ndarray, state: JointState, live: LiveGait
) -> DriveCycle:
    return DriveCycle(
        cycle=k,
        gait_time_s=k * DT,
        target_rad=target,
        command_rad=command,
        state=state,
        body=None,
        amplitude=1.0,
        scored=True,
        period_s=DT,
        overrun=False,
        achieved_rate_hz=1.0 / DT,
        status=live.status(),
        keys=(),
    )


def live_gait(robot: RobotConfig) -> LiveGait:
    live = LiveGait(
        robot.joint_count,
        lower_rad=robot.lower_rad,
        upper_rad=robot.upper_rad,
        max_speed_rad_s=robot.max_speed_rad_s,
        period_s=DT,
    )
    live.start(np.zeros(robot.joint_count))
    live.select(GAIT[robot.name])
    live.set_controls(LiveControls(speed=1.0, turn=0.25))
    for k in range(300):  # past the blend and the ramps: steady driving
        live.command(k * DT)
    return live


def timed(step: Callable[[int], object], cycles: int) -> float:
    start = time.perf_counter()
    for k in range(cycles):
        step(k)
    return (time.perf_counter() - start) / cycles * 1e6


def cases(robot: RobotConfig) -> tuple[dict[str, Callable[[int], object]], DriveDisplay]:
    n = robot.joint_count
    gait = make_gait(GAIT[robot.name], n)
    safety = SafetyLayer.for_robot(robot)
    safety.reset(np.zeros(n))
    live = live_gait(robot)
    state = JointState(0.0, np.zeros(n), np.zeros(n), np.zeros(n))
    display = DriveDisplay(
        io.StringIO(),
        title="bench",
        gaits=[GAIT[robot.name]],
        gait_index=lambda: 0,
        notice=lambda: "",
        rate_hz=100.0,
        servo_ids=robot.servo_ids,
        health=dict,
        alerts=tuple,
        overruns=lambda: 0,
    )
    record = drive_cycle(0, np.zeros(n), np.zeros(n), state, live)
    start = 3.0

    def plain(k: int) -> object:
        return safety.filter(gait.command(start + k * DT), DT)

    def driven(k: int) -> object:
        return safety.filter(live.command(start + k * DT), DT)

    def with_status(k: int) -> object:
        target = live.command(start + k * DT)
        command = safety.filter(target, DT)
        return drive_cycle(k, target, command, state, live)

    def shown(k: int) -> object:
        display(record)
        return None

    steps = {"gait": plain, "live": driven, "live+status": with_status, "display": shown}
    return steps, display


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--cycles", type=int, default=2000)
    args = parser.parse_args()
    for name in ("snake8", "snake12"):
        robot = load_robot(name)
        results: dict[str, list[float]] = {}
        ratios = []
        for _ in range(args.rounds):
            steps, display = cases(robot)
            order = list(steps)
            random.shuffle(order)
            round_us = {key: timed(steps[key], args.cycles) for key in order}
            display.close()
            for key in steps:
                results.setdefault(key, []).append(round_us[key])
            ratios.append(round_us["live"] / round_us["gait"])
        line = "  ".join(f"{k} {statistics.median(v):6.1f} us" for k, v in results.items())
        print(f"{name:8} {line}  live/gait {statistics.median(ratios):.1f}x")


if __name__ == "__main__":
    main()
