"""Gait-based compliance on the twin: the same gait with compliance off and on, per terrain.

For each terrain (``--terrain``, repeatable; the pegs and pipe cases of docs/compliance.md by
default) the gait runs through ``run_gait`` and its safety layer twice, without and with
``CompliantGait`` (snakebot.control.compliance), and the bench prints the centre of mass's
distance over the gait time (m/s), the servos' stall time (``StallMeter``: servo-seconds at
>= 50 % of stall torque and < 5 % of no-load speed) and the peak servo torque, then the ratios.

    python tools/bench_compliance.py                                  # the docs' table
    python tools/bench_compliance.py --terrain pegs:density=100,seed=1 --duration 20 --json
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.control.compliance import ComplianceSettings, CompliantGait, StallMeter
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait

DEFAULT_TERRAINS = (
    "pegs",
    "pegs:density=100,seed=1",
    "pegs:density=100,seed=2",
    "pegs:density=100,seed=3",
    "pegs:density=150,seed=1",
    "pegs:layout=lattice,spacing_m=0.12",
)


def run_case(
    robot_name: str, gait_name: str, terrain: str, duration_s: float, comply: bool
) -> dict[str, float]:
    """One run: speed (m/s of the centre of mass over the gait time), stall and peak torque."""
    robot = load_robot(robot_name)
    physics = robot.servo.physics
    base = make_gait(
        gait_name, robot.joint_count, {}, lower_rad=robot.lower_rad, upper_rad=robot.upper_rad
    )
    gait = CompliantGait(base, physics.stall_torque_nm, ComplianceSettings()) if comply else base
    meter = StallMeter(physics.stall_torque_nm, physics.no_load_speed_rad_s)
    observers = [meter, *([gait.observe] if isinstance(gait, CompliantGait) else [])]
    with TwinBackend(robot, terrain=terrain) as twin:
        start = twin.body_state().com_m.copy()
        run_gait(
            twin,
            gait,
            SafetyLayer.for_robot(robot),
            RunPlan(duration_s, ramp_out=False),
            RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
            observers=observers,
        )
        end = twin.body_state().com_m
    return {
        "speed_m_s": float(np.hypot(*(end - start)[:2])) / duration_s,
        **meter.summary(),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="snake8")
    parser.add_argument("--gait", default="serpenoid")
    parser.add_argument("--terrain", action="append", help="repeatable (default: the docs' set)")
    parser.add_argument("--duration", type=float, default=20.0, help="s of gait time")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    rows = []
    for terrain in args.terrain or DEFAULT_TERRAINS:
        began = time.perf_counter()
        off = run_case(args.robot, args.gait, terrain, args.duration, comply=False)
        on = run_case(args.robot, args.gait, terrain, args.duration, comply=True)
        rows.append(
            {"terrain": terrain, "off": off, "on": on, "wall_s": time.perf_counter() - began}
        )
        if not args.json:
            stall_ratio = (
                on["servo_stall_s"] / off["servo_stall_s"] if off["servo_stall_s"] else None
            )
            print(
                f"| {terrain} | {off['speed_m_s']:.3f} | {on['speed_m_s']:.3f} "
                f"| {on['speed_m_s'] / off['speed_m_s']:.2f} "
                f"| {off['servo_stall_s']:.2f} | {on['servo_stall_s']:.2f} "
                f"| {'-' if stall_ratio is None else f'{stall_ratio:.2f}'} "
                f"| {off['peak_servo_torque_nm']:.2f} | {on['peak_servo_torque_nm']:.2f} |",
                flush=True,
            )
    if args.json:
        print(json.dumps({"robot": args.robot, "gait": args.gait, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
