"""Gait-based compliance on the twin: the same gait with compliance off and on, per terrain.

For each case (robot, gait, terrain; docs/compliance.md's 16 by default, or ``--terrain``,
repeatable, for ``--robot`` and ``--gait``) the gait runs through ``run_gait`` and its safety
layer twice, without and with ``CompliantGait`` (snakebot.control.compliance), and the bench
prints the centre of mass's distance over the gait time (m/s), the servos' stall time
(``StallMeter``: servo-seconds at >= 50 % of stall torque and < 5 % of no-load speed) and the
peak servo torque, then the ratios, as rows of the docs' table. ``--set NAME=VALUE``
(repeatable) changes a ``ComplianceSettings`` field of the compliant run, e.g.
``--set phase_gain=2`` to let the phase yield too (off by default). A robot ``NAME@SERVO`` is
the robot file ``NAME`` with its ``servo`` changed to ``SERVO`` (``snake8@XM430-W350``).

    python tools/bench_compliance.py                                  # the docs' table
    python tools/bench_compliance.py --terrain pegs:density=100,seed=1 --duration 20 --json
    python tools/bench_compliance.py --set phase_gain=2                # the phase table
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import re
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from snakebot.backends.twin import TwinBackend
from snakebot.config import RobotConfig, load_robot
from snakebot.config.loader import resolve_robot_path
from snakebot.control.compliance import ComplianceSettings, CompliantGait, StallMeter
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait

SNAKE8_TERRAINS = (
    "pegs",
    "pegs:density=60,seed=1",
    "pegs:density=100,seed=1",
    "pegs:density=100,seed=2",
    "pegs:density=100,seed=3",
    "pegs:density=100,seed=4",
    "pegs:density=100,seed=5",
    "pegs:layout=lattice,spacing_m=0.12",
    "pipe",
    "pipe:inner_diameter_m=0.1",
)
DOCS_CASES: tuple[tuple[str, str, str], ...] = (
    *(("snake8", "serpenoid", terrain) for terrain in SNAKE8_TERRAINS),
    ("snake12", "sidewinding", "pipe"),
    ("snake12", "sidewinding", "pipe:inner_diameter_m=0.1"),
    ("snake12", "sidewinding", "pegs:density=100,seed=1"),
    ("snake8@XM430-W350", "serpenoid", "pegs:density=100,seed=1"),
    ("snake8@XM430-W350", "serpenoid", "pegs:density=100,seed=2"),
    ("snake8@XM430-W350", "serpenoid", "pegs:layout=lattice,spacing_m=0.12"),
)
"""docs/compliance.md's table: (robot, gait, terrain)."""


def load_case_robot(spec: str) -> RobotConfig:
    """``NAME`` or ``NAME@SERVO``: the robot file, with its ``servo`` key changed to SERVO."""
    name, _, servo = spec.partition("@")
    if not servo:
        return load_robot(name)
    path = resolve_robot_path(name)
    text = re.sub(r'(?m)^servo = ".*"', f'servo = "{servo}"', path.read_text(), count=1)
    with tempfile.TemporaryDirectory() as folder:  # servos are found on the search path
        copy = Path(folder) / path.name
        copy.write_text(text)
        return load_robot(copy)


def parse_setting(text: str) -> tuple[str, float]:
    """``NAME=VALUE`` for one numeric ComplianceSettings field; ValueError otherwise."""
    name, _, value = text.partition("=")
    fields = {f.name for f in dataclasses.fields(ComplianceSettings)}
    if name not in fields or name in ("amplitude_range", "windows"):
        raise ValueError(f"--set {text!r}: not a numeric compliance setting")
    return name, float(value)


def run_case(
    robot_name: str,
    gait_name: str,
    terrain: str,
    duration_s: float,
    comply: bool,
    settings: ComplianceSettings | None = None,
) -> dict[str, float]:
    """One run: speed (m/s of the centre of mass over the gait time), stall and peak torque.

    ``settings`` are the compliant run's (ComplianceSettings' defaults when None)."""
    robot = load_case_robot(robot_name)
    physics = robot.servo.physics
    base = make_gait(
        gait_name, robot.joint_count, {}, lower_rad=robot.lower_rad, upper_rad=robot.upper_rad
    )
    gait = CompliantGait(base, physics.stall_torque_nm, settings) if comply else base
    meter = StallMeter(physics.stall_torque_nm, physics.no_load_speed_rad_s)
    observers: list[Callable[[CycleRecord], None]] = [meter]
    if isinstance(gait, CompliantGait):
        observers.append(gait.observe)
    twin = TwinBackend(robot, terrain=terrain)
    with twin:
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
    parser.add_argument("--robot", default="snake8", help="with --terrain; NAME or NAME@SERVO")
    parser.add_argument("--gait", default="serpenoid", help="with --terrain")
    parser.add_argument("--terrain", action="append", help="repeatable (default: the docs' set)")
    parser.add_argument(
        "--peg-seeds",
        type=seed_range,
        metavar="FIRST-LAST",
        help="instead of --terrain: pegs:density=100,seed=N for N from FIRST to LAST",
    )
    parser.add_argument("--duration", type=float, default=20.0, help="s of gait time")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        type=parse_setting,
        metavar="NAME=VALUE",
        help="a ComplianceSettings field of the compliant run (repeatable)",
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    settings = ComplianceSettings(**dict(args.set))
    terrains = args.terrain or [f"pegs:density=100,seed={n}" for n in args.peg_seeds or ()]
    cases = [(args.robot, args.gait, terrain) for terrain in terrains] if terrains else DOCS_CASES
    rows = []
    heading = None
    for robot, gait, terrain in cases:
        if not args.json and (robot, gait) != heading:
            heading = (robot, gait)
            print(f"{robot}, {gait}:", flush=True)
        began = time.perf_counter()
        off = run_case(robot, gait, terrain, args.duration, comply=False)
        on = run_case(robot, gait, terrain, args.duration, comply=True, settings=settings)
        rows.append(
            {
                "robot": robot,
                "gait": gait,
                "terrain": terrain,
                "off": off,
                "on": on,
                "wall_s": time.perf_counter() - began,
            }
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
        print(json.dumps({"settings": dataclasses.asdict(settings), "rows": rows}, indent=1))
    else:
        print(tally(rows))
    return 0


JAM_S = 0.5
"""A case jams without compliance when its servos stall for over this many servo-seconds."""


def tally(rows: list[dict[str, object]]) -> str:
    """One line over the rows: how many jams compliance halved at under 20 % speed loss, the
    stall time summed over the cases off and on (servo-s) and the median speed ratio."""
    pairs = [(row["off"], row["on"]) for row in rows]
    off_on = [(o, n) for o, n in pairs if isinstance(o, dict) and isinstance(n, dict)]
    jams = [(o, n) for o, n in off_on if o["servo_stall_s"] > JAM_S]
    halved = sum(
        n["servo_stall_s"] <= 0.5 * o["servo_stall_s"] and n["speed_m_s"] >= 0.8 * o["speed_m_s"]
        for o, n in jams
    )
    ratios = [n["speed_m_s"] / o["speed_m_s"] for o, n in off_on if o["speed_m_s"] > 0]
    stall_off = sum(o["servo_stall_s"] for o, _ in off_on)
    stall_on = sum(n["servo_stall_s"] for _, n in off_on)
    median = float(np.median(ratios)) if ratios else float("nan")
    return (
        f"{len(off_on)} cases, {len(jams)} jams (stall off > {JAM_S} servo-s): {halved} halved "
        f"at under 20 % speed loss; stall in all {stall_off:.2f} -> {stall_on:.2f} servo-s; "
        f"median speed ratio {median:.2f}"
    )


def seed_range(text: str) -> range:
    """``FIRST-LAST`` (inclusive) as a range; ValueError otherwise."""
    first, _, last = text.partition("-")
    return range(int(first), int(last or first) + 1)


if __name__ == "__main__":
    raise SystemExit(main())
