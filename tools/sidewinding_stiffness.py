"""Sidewinding direction against servo stiffness: snake12, CMU sidewinding, 20 s per P gain.

    .venv/bin/python tools/sidewinding_stiffness.py [P ...]

Prints one JSON line per P gain (D stays at snake12's 4000): distance, heading, the head's total
turn and body lengths per cycle. The table in docs/physics.md is its output.
"""

from __future__ import annotations

import dataclasses
import json
import sys

from snakebot.backends.twin import TwinBackend
from snakebot.config import RobotConfig, load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait

DEFAULT_GAINS = (320, 640, 960, 1280, 1920, 2560, 5120)


def sidewind(p_gain: int, duration_s: float = 20.0) -> dict[str, object]:
    """One run of snake12's sidewinding with Position P Gain ``p_gain``; its summary."""
    base = load_robot("snake12")
    registers = dataclasses.replace(base.gain_registers, position_p=p_gain)
    robot: RobotConfig = dataclasses.replace(base, gains=base.servo.gains_of(registers))
    gait = make_gait("sidewinding", robot.joint_count)
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    with TwinBackend(robot) as twin:
        result = run_gait(twin, gait, SafetyLayer.for_robot(robot), RunPlan(duration_s), metrics)
    return result.summary


def main(argv: list[str]) -> None:
    for p_gain in [int(a) for a in argv] or DEFAULT_GAINS:
        s = sidewind(p_gain)
        keys = ("distance_m", "heading_deg", "turn_deg", "body_lengths_per_cycle")
        row = {key: round(float(s[key]), 3) for key in keys}  # type: ignore[arg-type]
        print(json.dumps({"P": p_gain, **row}), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
