"""Benchmark: the twin's terrains and ground friction models.

Part 1, ``friction`` (issue 12's Done-when, snake8, serpenoid lateral undulation, 6 s): the same
command sequence on each ground, bare ``mj_step(m, d, 5)`` per 10 ms control period, rounds in
shuffled order; steps/s as the median over rounds and ratios taken within each round.
  pairs/plane        the default: capsule-plane pairs, axial 0.05, lateral 1.0
  iso/plane          isotropic pairs, mu 1.0 (the speed reference "isotropic on the plane")
  scale-c/plane      scale model in C, the robot's coefficients
  iso/field          isotropic (mu 1.0) on a flat height field (rough:roughness_m=0)
  scale-c/field      scale model in C on the same field
  scale-numpy/field  scale model in numpy on the same field
  pairs/field        the robot's pairs on the same field (world-aligned: the issue's defect)

Part 2, ``table``: per terrain (defaults) and robot, lateral undulation, sidewinding and rolling
where the robot has the joints for them, played like ``snakebot run`` for ``--seconds``:
distance, body lengths per gait cycle, success (1 body length within the time limit, and the
time it took), MuJoCo warnings (or divergence), steps/s.

    python tools/bench_terrain.py [friction|table|all] [--rounds 5] [--seconds 20]
"""

from __future__ import annotations

import argparse
import os
import random
import statistics
import time
from collections.abc import Callable
from typing import Any

import mujoco
import numpy as np

from snakebot.backends.twin import GroundFriction, TwinBackend
from snakebot.backends.twin.terrain import BUILT_IN_TERRAINS
from snakebot.config import RobotConfig, load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.errors import SimulationDivergedError
from snakebot.gaits import make_gait

FIELD = "rough:roughness_m=0"
ISOTROPIC = GroundFriction(1.0, 1.0)
GROUNDS: dict[str, dict[str, Any]] = {
    "pairs/plane": {},
    "iso/plane": {"friction": ISOTROPIC},
    "scale-c/plane": {"friction_model": "scale"},
    "iso/field": {"terrain": FIELD, "friction": ISOTROPIC, "friction_model": "pairs"},
    "scale-c/field": {"terrain": FIELD},
    "scale-numpy/field": {"terrain": FIELD, "numpy": True},
    "pairs/field": {"terrain": FIELD, "friction_model": "pairs"},
}


def bare_run(robot: RobotConfig, ground: dict[str, Any], seconds: float) -> tuple[float, float]:
    """(steps/s, COM distance in m) of serpenoid lateral undulation with ``ground``."""
    options = {k: v for k, v in ground.items() if k != "numpy"}
    os.environ["SNAKEBOT_SCALE_FRICTION"] = "numpy" if ground.get("numpy") else "c"
    gait = make_gait("serpenoid", robot.joint_count)
    with TwinBackend(robot, **options) as twin:
        model, data = twin.model, twin.data
        steps = twin.steps_for(0.01)
        cycles = round(seconds / 0.01)
        targets = [
            min(1.0, k / 100) * gait.command(k * 0.01) for k in range(cycles)
        ]  # a 1 s amplitude ramp, computed before the clock starts
        start_com = twin.body_state().com_m
        begin = time.perf_counter()
        for target in targets:
            data.ctrl[:] = target
            mujoco.mj_step(model, data, steps)
        wall = time.perf_counter() - begin
        moved = float(np.linalg.norm((twin.body_state().com_m - start_com)[:2]))
    return cycles * steps / wall, moved


def friction_part(rounds: int) -> None:
    """Part 1: speed and cost of the friction models, side by side."""
    robot = load_robot("snake8")
    rates: dict[str, list[float]] = {name: [] for name in GROUNDS}
    ratios: dict[str, list[float]] = {"plane": [], "field": []}
    distance: dict[str, float] = {}
    for _ in range(rounds):
        order = list(GROUNDS)
        random.shuffle(order)
        this: dict[str, float] = {}
        for name in order:
            this[name], distance[name] = bare_run(robot, GROUNDS[name], 6.0)
            rates[name].append(this[name])
        ratios["plane"].append(this["scale-c/plane"] / this["iso/plane"])
        ratios["field"].append(this["scale-c/field"] / this["iso/field"])
    print(f"snake8, serpenoid, 6 s, {rounds} rounds (median steps/s; distance is deterministic)")
    print(f"{'ground':20s} {'steps/s':>9s} {'distance m':>11s}")
    for name in GROUNDS:
        print(f"{name:20s} {statistics.median(rates[name]):9.0f} {distance[name]:11.3f}")
    print(
        f"scale/iso steps/s: plane {statistics.median(ratios['plane']):.2f}, "
        f"same field {statistics.median(ratios['field']):.2f}"
    )
    print(
        f"scale on the field / pairs on the plane distance: "
        f"{distance['scale-c/field'] / distance['pairs/plane']:.3f}; "
        f"/ scale on the plane: {distance['scale-c/field'] / distance['scale-c/plane']:.3f}"
    )


GAITS = {
    "snake8": ("serpenoid",),
    "snake12": ("lateral_undulation", "sidewinding", "rolling"),
}


def play(robot: RobotConfig, terrain: str, gait_name: str, seconds: float) -> dict[str, Any]:
    """One row of the table."""
    os.environ["SNAKEBOT_SCALE_FRICTION"] = "c"
    gait = make_gait(gait_name, robot.joint_count)
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    twin = TwinBackend(robot, terrain=terrain)
    reached: list[float] = []
    row: dict[str, Any] = {"terrain": terrain, "robot": robot.name, "gait": gait_name}
    with twin:
        start = twin.body_state().com_m

        def watch(cycle: int, gait_time_s: float) -> None:
            moved = np.linalg.norm((twin.body_state().com_m - start)[:2])
            if not reached and moved >= robot.body_length_m:
                reached.append(gait_time_s)

        plan = RunPlan(seconds, ramp_out=False)
        begin = time.perf_counter()
        try:
            result = run_gait(
                twin, gait, SafetyLayer.for_robot(robot), plan, metrics, on_cycle=watch
            )
        except SimulationDivergedError as exc:
            row.update(error=f"diverged at {exc.time_s:.2f} s")
            return row
        wall = time.perf_counter() - begin
        warnings = int(sum(w.number for w in twin.data.warning))
        summary = result.summary
        row.update(
            distance_m=float(summary["distance_m"]),  # type: ignore[arg-type]
            bl_per_cycle=float(summary["body_lengths_per_cycle"] or 0.0),  # type: ignore[arg-type]
            success=bool(reached),
            time_to_1bl_s=reached[0] if reached else None,
            warnings=warnings,
            steps_per_s=float(twin.data.time) / float(twin.model.opt.timestep) / wall,
            model=("scale" if twin.model.npair == 0 else "pairs"),
        )
    return row


def table_part(seconds: float, only: Callable[[str], bool] = lambda name: True) -> None:
    """Part 2: the terrain table (markdown)."""
    print(f"\n{seconds:g} s per run; success = 1 body length within {seconds:g} s")
    print(
        "| terrain | robot | gait | friction | distance m | BL/cycle | success (time) "
        "| warnings | steps/s |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for terrain in BUILT_IN_TERRAINS:
        if not only(terrain):
            continue
        for robot_name, gaits in GAITS.items():
            robot = load_robot(robot_name)
            for gait in gaits:
                row = play(robot, terrain, gait, seconds)
                if "error" in row:
                    print(f"| {terrain} | {robot_name} | {gait} | | {row['error']} | | | | |")
                    continue
                success = f"yes ({row['time_to_1bl_s']:.1f} s)" if row["success"] else "no"
                print(
                    f"| {terrain} | {robot_name} | {gait} | {row['model']} "
                    f"| {row['distance_m']:.2f} | {row['bl_per_cycle']:.2f} | {success} "
                    f"| {row['warnings']} | {row['steps_per_s']:.0f} |",
                    flush=True,
                )


def main() -> None:
    """Run the parts asked for and print their tables."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("part", nargs="?", choices=("friction", "table", "all"), default="all")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--terrain", action="append", help="table: only these terrains")
    args = parser.parse_args()
    if args.part in ("friction", "all"):
        friction_part(args.rounds)
    if args.part in ("table", "all"):
        wanted = set(args.terrain or BUILT_IN_TERRAINS)
        table_part(args.seconds, lambda name: name in wanted)


if __name__ == "__main__":
    main()
