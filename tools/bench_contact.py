"""Benchmark: the twin's ground-contact models against each other, for speed and for physics.

Issue 20 item 8. Each contact model of snake8 on the floor plane, side by side in one process:
  pairs6-elliptic    the default: one capsule-plane <pair> per module, condim 6 (sliding,
                     spin, rolling friction: passive wheels do not roll sideways), elliptic cone
  pairs6-pyramidal   the same pairs with MuJoCo's pyramidal friction cone
  pairs3-elliptic    condim 3 pairs (no rolling friction), elliptic cone
  pairs3-pyramidal   condim 3 pairs, pyramidal cone
  scale              the scale friction model (friction/scale.py, its C callback): condim 1
                     contacts and a friction force per module

Speed (``--rounds``, shuffled order each round): steps/s of a bare ``mj_step(m, d, 5)`` per 10 ms
control period, serpenoid ctrl on the robot's own ground; the ratio to the default is taken in
each round, medians over rounds (min-max).

Physics, each model once (deterministic), on what the docs validate (docs/twin.md):
  mu along / across  the Coulomb reference: a straight 5-module snake pushed with 1.5 m g on a
                     (0.1, 1.0) ground reads mu = 0.10 along and 0.97 across with the default
                     (tests/integration/twin/test_model_builder.py)
  no-slip            snake8, (0.02, 1.0), serpenoid 20 s as `snakebot run`: distance per gait
                     cycle over the no-slip bound (L/K) J0(a) (0.90 with the default;
                     tests/integration/control/test_locomotion.py asks >= 0.8)
  own ground         snake8 on its own ground (0.05 / 1.0) 20 s: distance (4.59 m)
  isotropic          snake8 on (1.0, 1.0) 20 s: distance (0.12 m)

    python tools/bench_contact.py [--rounds 5] [--seconds 4] [--physics-seconds 20]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import random
import statistics
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import mujoco
import numpy as np
from scipy.special import j0

import snakebot.backends.twin.backend as twin_module
from snakebot.backends.twin import GroundFriction, TwinBackend
from snakebot.backends.twin import model_builder as builder
from snakebot.config import RobotConfig, load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait

RATE_HZ = 100.0
VARIANTS = ("pairs6-elliptic", "pairs6-pyramidal", "pairs3-elliptic", "pairs3-pyramidal", "scale")


def build_variant(variant: str, robot: RobotConfig, **options: Any) -> mujoco.MjModel:
    """The twin of ``robot`` as ``build_model`` makes it, with the contact model ``variant``."""
    if variant == "scale":
        options["friction_model"] = "scale"
        return builder.build_model(robot, **options)[0]
    options["friction_model"] = "pairs"
    spec = builder.build_spec(robot, **options)
    condim = int(variant[5])
    if variant.endswith("pyramidal"):
        spec.option.cone = mujoco.mjtCone.mjCONE_PYRAMIDAL
    for pair in spec.pairs:
        if pair.condim == 6 or pair.condim == 3:
            pair.condim = condim
    builder.add_actuators(spec, robot)
    return builder.compile_spec(spec, robot)


@contextmanager
def twin_with(variant: str) -> Iterator[None]:
    """TwinBackend builds its model with the contact model ``variant`` inside the block."""
    original = twin_module.build_model

    def build(robot: RobotConfig, **options: Any) -> tuple[mujoco.MjModel, None]:
        return build_variant(variant, robot, **options), None

    twin_module.build_model = build  # type: ignore[assignment]
    try:
        yield
    finally:
        twin_module.build_model = original


def bare_steps_per_s(model: mujoco.MjModel, joints: int, seconds: float) -> float:
    data = mujoco.MjData(model)
    per_cycle = round(1.0 / RATE_HZ / model.opt.timestep)
    cycles = round(seconds * RATE_HZ)
    phase = 0.7 * np.arange(joints)
    start = time.perf_counter()
    for k in range(cycles):
        data.ctrl[:] = 0.4 * np.sin(np.pi * k / RATE_HZ - phase)
        mujoco.mj_step(model, data, per_cycle)
    return cycles * per_cycle / (time.perf_counter() - start)


def robot_with_joints(joints: int) -> RobotConfig:
    base = load_robot("snake8")
    chain = tuple(dataclasses.replace(base.joints[0], servo_id=i + 1) for i in range(joints))
    return dataclasses.replace(base, joints=chain)


def drag_friction(
    variant: str, direction: np.ndarray, friction: GroundFriction, per_step: bool
) -> float:
    """Effective mu of a straight, stiff 5-module snake pushed with 1.5 m g.

    ``per_step`` False: the test's push, ``xfrc_applied`` set once (the scale model overwrites
    it every step, so there it reads no motion); True: ``qfrc_applied`` at each body's COM,
    recomputed every physics step."""
    robot = robot_with_joints(4)
    with twin_with(variant), TwinBackend(robot, friction=friction) as twin:
        model, data = twin.model, twin.data
        mass = robot.total_mass_kg
        twin.advance(0.1)
        v0 = data.qvel[:2].copy()
        push = 1.5 * mass * 9.81
        if not per_step:
            for body in range(1, model.nbody):
                data.xfrc_applied[body, :2] = direction * push * model.body_mass[body] / mass
            twin.advance(0.3)
            accel = (data.qvel[:2] - v0) @ direction / 0.3
            return float((push - mass * accel) / (mass * 9.81))
        force, zero = np.zeros(3), np.zeros(3)
        timestep = float(model.opt.timestep)
        for _ in range(round(0.3 / timestep)):
            data.qfrc_applied[:] = 0.0
            for body in range(1, model.nbody):
                force[:2] = direction * push * model.body_mass[body] / mass
                mujoco.mj_applyFT(
                    model, data, force, zero, data.xipos[body], body, data.qfrc_applied
                )
            twin.advance(timestep)
        accel = (data.qvel[:2] - v0) @ direction / 0.3
    return float((push - mass * accel) / (mass * 9.81))


def serpenoid_run(variant: str, friction: GroundFriction | None, seconds: float) -> dict[str, Any]:
    return gait_run(variant, "snake8", "serpenoid", friction, seconds)


def gait_run(
    variant: str, robot_name: str, gait_name: str, friction: GroundFriction | None, seconds: float
) -> dict[str, Any]:
    """A run as `snakebot run` plays it; the summary plus the head's roll in turns."""
    robot = load_robot(robot_name)
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    gait = make_gait(gait_name, robot.joint_count)
    roll = [0.0, 0.0]
    with twin_with(variant), TwinBackend(robot, friction=friction) as twin:
        head = twin.model.body("link0").id

        def track_roll(cycle: int, gait_time_s: float) -> None:
            matrix = twin.data.xmat[head]
            angle = math.atan2(matrix[7], matrix[8])
            roll[0] += math.remainder(angle - roll[1], 2 * math.pi)
            roll[1] = angle

        result = run_gait(
            twin,
            gait,
            SafetyLayer.for_robot(robot),
            RunPlan(duration_s=seconds),
            metrics,
            on_cycle=track_roll,
        )
    result.summary["head_roll_turns"] = roll[0] / (2 * math.pi)
    return result.summary


def no_slip_per_cycle() -> float:
    robot = load_robot("snake8")
    waves = robot.link_count * 0.7 / (2 * math.pi)
    return float(robot.body_length_m / waves * j0(0.4 / (2 * math.sin(0.35))))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=4.0, help="simulated s per speed block")
    parser.add_argument("--physics-seconds", type=float, default=20.0)
    parser.add_argument("--skip-physics", action="store_true")
    args = parser.parse_args()
    robot = load_robot("snake8")
    models = {v: build_variant(v, robot) for v in VARIANTS}
    speed: dict[str, list[float]] = {v: [] for v in VARIANTS}
    ratio: dict[str, list[float]] = {v: [] for v in VARIANTS}
    for _ in range(args.rounds):
        order = list(VARIANTS)
        random.shuffle(order)
        got = {v: bare_steps_per_s(models[v], robot.joint_count, args.seconds) for v in order}
        for v in VARIANTS:
            speed[v].append(got[v])
            ratio[v].append(got[v] / got["pairs6-elliptic"])
    physics: dict[str, dict[str, float]] = {}
    if not args.skip_physics:
        coulomb = GroundFriction(0.1, 1.0)
        bound = no_slip_per_cycle()
        for v in VARIANTS:
            strong = serpenoid_run(v, GroundFriction(0.02, 1.0), args.physics_seconds)
            own = serpenoid_run(v, None, args.physics_seconds)
            iso = serpenoid_run(v, GroundFriction(1.0, 1.0), args.physics_seconds)
            physics[v] = {
                "along": drag_friction(v, np.array([1.0, 0.0]), coulomb, False),
                "across": drag_friction(v, np.array([0.0, 1.0]), coulomb, False),
                "along_q": drag_friction(v, np.array([1.0, 0.0]), coulomb, True),
                "across_q": drag_friction(v, np.array([0.0, 1.0]), coulomb, True),
                "no_slip": float(strong["distance_m"]) / float(strong["cycles"]) / bound,
                "heading": float(strong["heading_deg"]),
                "own": float(own["distance_m"]),
                "own_cot": float(own["cost_of_transport"] or math.nan),
                "iso": float(iso["distance_m"]),
            }
    snake12_part(args)
    print(f"snake8, {args.rounds} rounds x {args.seconds:g} s simulated per speed block\n")
    print(
        "| contact model | steps/s | ÷ default (min-max) "
        "| mu along / across (0.1 / 1.0): test's push "
        "| per-step push "
        "| no-slip fraction (heading) | own ground, m (COT) | isotropic, m |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for v in VARIANTS:
        cells = [
            f"{statistics.median(speed[v]):,.0f}",
            f"{statistics.median(ratio[v]):.2f} ({min(ratio[v]):.2f}-{max(ratio[v]):.2f})",
        ]
        if v in physics:
            p = physics[v]
            cells += [
                f"{p['along']:.2f} / {p['across']:.2f}",
                f"{p['along_q']:.2f} / {p['across_q']:.2f}",
                f"{p['no_slip']:.2f} ({p['heading']:.0f}°)",
                f"{p['own']:.2f} ({p['own_cot']:.2f})",
                f"{p['iso']:.3f}",
            ]
        else:
            cells += ["", "", "", "", ""]
        print(f"| {v} | " + " | ".join(cells) + " |")


SNAKE12 = ("pairs3-elliptic", "pairs3-pyramidal", "scale")


def snake12_part(args: argparse.Namespace) -> None:
    """snake12 (bare modules, isotropic mu 0.7: condim 3 pairs by default)."""
    robot = load_robot("snake12")
    models = {v: build_variant(v, robot) for v in SNAKE12}
    speed: dict[str, list[float]] = {v: [] for v in SNAKE12}
    ratio: dict[str, list[float]] = {v: [] for v in SNAKE12}
    for _ in range(args.rounds):
        order = list(SNAKE12)
        random.shuffle(order)
        got = {v: bare_steps_per_s(models[v], robot.joint_count, args.seconds) for v in order}
        for v in SNAKE12:
            speed[v].append(got[v])
            ratio[v].append(got[v] / got["pairs3-elliptic"])
    print(f"snake12, {args.rounds} rounds x {args.seconds:g} s simulated per speed block\n")
    print(
        "| contact model | steps/s | ÷ default (min-max) | sidewinding BL/cycle (heading) "
        "| rolling: m (heading), head turns |"
    )
    print("|---|---|---|---|---|")
    for v in SNAKE12:
        cells = [
            f"{statistics.median(speed[v]):,.0f}",
            f"{statistics.median(ratio[v]):.2f} ({min(ratio[v]):.2f}-{max(ratio[v]):.2f})",
        ]
        if not args.skip_physics:
            side = gait_run(v, "snake12", "sidewinding", None, args.physics_seconds)
            rolling = gait_run(v, "snake12", "rolling", None, args.physics_seconds)
            cells += [
                f"{float(side['body_lengths_per_cycle']):.2f} ({float(side['heading_deg']):.0f}°)",
                f"{float(rolling['distance_m']):.2f} ({float(rolling['heading_deg']):.0f}°), "
                f"{float(rolling['head_roll_turns']):.1f}",
            ]
        print(f"| {v} | " + " | ".join(cells) + " |")
    print()


if __name__ == "__main__":
    main()
