"""Benchmark: a mass-spring body under `snakebot run` against bare mj_step of the same model.

For bodies of 6, 10 and 20 segments (Miller's snake springs, three channels per segment, 1 ms
physics, 100 Hz control), each round runs, back to back in one process on one pinned core and in
shuffled order:
  snakebot        the path of `snakebot run --gait undulation` (gait -> safety -> SoftBodyBackend
                  with Miller's directional rule after every step, metrics)
  snakebot_off    the same with --directional off
  bare_step       the MJCF `snakebot model` exports, loaded by MuJoCo; the same spring rest lengths
                  (precomputed) written to ctrl every 10 ms, one mj_step() call per physics step
  bare_step+rule  bare_step plus DirectionalFriction.apply after every step
Ratios are taken within each round, then the median over rounds is reported with its range.
Real time x = simulated seconds per wall second (and per CPU second of the process: on
a shared machine the CPU figure is what one free core would give).

    python tools/bench_softbody.py [--rounds 7] [--seconds 5] [--sizes 6,10,20] [--cpu 0]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import random
import statistics
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np

from snakebot.backends.softbody import SoftBodyBackend, build_body_spec
from snakebot.backends.softbody.friction import DirectionalFriction
from snakebot.backends.softbody.lattice import build_lattice
from snakebot.backends.softbody.model import point_name
from snakebot.backends.softbody.muscles import ChannelLayout, MuscleMap
from snakebot.config.body import BodyConfig
from snakebot.config.body_loader import load_body
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer, smooth_ramp
from snakebot.gaits import make_gait

RATE_HZ = 100.0
VARIANTS = ("snakebot", "snakebot_off", "bare_step", "bare_step+rule")


def body_with(segments: int) -> BodyConfig:
    body = load_body("snake")
    return dataclasses.replace(body, lattice=dataclasses.replace(body.lattice, segments=segments))


def run_snakebot(body: BodyConfig, seconds: float, directional: bool) -> tuple[float, float]:
    gait = make_gait("undulation", body.joint_count)
    metrics = RunMetrics(body.joint_count, body.body_length_m, body.total_mass_kg)
    plan = RunPlan(duration_s=seconds, rate_hz=RATE_HZ, ramp_out=False)
    with SoftBodyBackend(body, directional=directional) as backend:
        start, cpu = time.perf_counter(), time.process_time()
        run_gait(backend, gait, SafetyLayer.for_robot(body), plan, metrics)
        return seconds / (time.perf_counter() - start), seconds / (time.process_time() - cpu)


def ctrl_schedule(body: BodyConfig, seconds: float) -> np.ndarray:
    """Rest lengths (cycles, springs) of the same gait with the same ramp, computed up front."""
    lat = body.lattice
    muscles = MuscleMap(
        build_lattice(lat.segments), lat.segment_length_m, lat.width_m, lat.height_m
    )
    layout = ChannelLayout(body.muscles.channels, lat.segments)
    gait = make_gait("undulation", body.joint_count)
    rows = []
    for k in range(round(seconds * RATE_HZ)):
        t = k / RATE_HZ
        yaw, pitch, axial = layout.split(smooth_ramp(t / body.safety.ramp_s) * gait.targets(t))
        rows.append(muscles.rest_lengths(yaw, pitch, axial, np.ones(lat.segments + 1)))
    return np.array(rows)


def run_bare(xml: Path, schedule: np.ndarray, rule: bool) -> tuple[float, float]:
    model = mujoco.MjModel.from_xml_path(str(xml))
    data = mujoco.MjData(model)
    points = model.nbody - 1
    geoms = np.array([model.geom(f"{point_name(i)}_geom").id for i in range(points)])
    bodies = np.array([model.body(point_name(i)).id for i in range(points)])
    friction = DirectionalFriction(geoms, model.ngeom, model.body_pos[bodies].copy())
    displacement, velocity = data.qpos.reshape(-1, 3), data.qvel.reshape(-1, 3)
    per_cycle = round(1.0 / RATE_HZ / model.opt.timestep)
    start, cpu = time.perf_counter(), time.process_time()
    for ctrl in schedule:
        data.ctrl[:] = ctrl
        for _ in range(per_cycle):
            mujoco.mj_step(model, data)
            if rule and data.ncon:
                friction.apply(displacement, velocity, data.contact.geom)
    simulated = len(schedule) * per_cycle * model.opt.timestep
    return simulated / (time.perf_counter() - start), simulated / (time.process_time() - cpu)


def micro(xml: Path, repeats: int = 2000) -> tuple[float, float]:
    """Median µs of one mj_step and of one DirectionalFriction.apply on a resting body."""
    model = mujoco.MjModel.from_xml_path(str(xml))
    data = mujoco.MjData(model)
    points = model.nbody - 1
    geoms = np.array([model.geom(f"{point_name(i)}_geom").id for i in range(points)])
    bodies = np.array([model.body(point_name(i)).id for i in range(points)])
    friction = DirectionalFriction(geoms, model.ngeom, model.body_pos[bodies].copy())
    mujoco.mj_forward(model, data)
    data.ctrl[:] = data.ten_length
    for _ in range(300):
        mujoco.mj_step(model, data)
    displacement, velocity = data.qpos.reshape(-1, 3), data.qvel.reshape(-1, 3)
    step, rule = [], []
    for _ in range(7):
        start = time.perf_counter()
        for _ in range(repeats):
            mujoco.mj_step(model, data)
        step.append((time.perf_counter() - start) / repeats * 1e6)
        contacts = data.contact.geom.copy()
        start = time.perf_counter()
        for _ in range(repeats):
            friction.apply(displacement, velocity, contacts)
        rule.append((time.perf_counter() - start) / repeats * 1e6)
    return statistics.median(step), statistics.median(rule)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--seconds", type=float, default=5.0, help="simulated seconds per block")
    parser.add_argument("--sizes", default="6,10,20", help="segments per body")
    parser.add_argument("--cpu", type=int, default=0, help="pin to this core (-1: do not pin)")
    args = parser.parse_args()
    if args.cpu >= 0 and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {args.cpu})
    sizes = [int(s) for s in args.sizes.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        bodies, xml, schedules = {}, {}, {}
        for n in sizes:
            bodies[n] = body_with(n)
            xml[n] = Path(tmp) / f"soft{n}.xml"
            xml[n].write_text(build_body_spec(bodies[n]).to_xml())
            schedules[n] = ctrl_schedule(bodies[n], args.seconds)
        # (wall, cpu) real-time factors per block; ratios within a round, on CPU time.
        results: dict[tuple[int, str], list[tuple[float, float]]] = {
            (n, v): [] for n in sizes for v in VARIANTS
        }
        ratios: dict[tuple[int, str], list[float]] = {
            (n, k): [] for n in sizes for k in ("snakebot", "rule")
        }
        for _ in range(args.rounds):
            for n in sizes:
                order = list(VARIANTS)
                random.shuffle(order)
                got: dict[str, tuple[float, float]] = {}
                for variant in order:
                    if variant.startswith("snakebot"):
                        got[variant] = run_snakebot(bodies[n], args.seconds, variant == "snakebot")
                    else:
                        got[variant] = run_bare(xml[n], schedules[n], variant.endswith("rule"))
                    results[(n, variant)].append(got[variant])
                ratios[(n, "snakebot")].append(got["snakebot"][1] / got["bare_step"][1])
                ratios[(n, "rule")].append(got["bare_step+rule"][1] / got["bare_step"][1])
        costs = {n: micro(xml[n]) for n in sizes}
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"{args.rounds} rounds, {args.seconds:g} s simulated per block, 1 ms steps, control "
        f"{RATE_HZ:g} Hz, pinned to core {args.cpu}, load average {load:.1f}; cells: times real "
        "time by the wall clock (by the process's CPU time)\n"
    )
    print(
        "| segments | points / springs | "
        + " | ".join(VARIANTS)
        + " | snakebot / bare_step (CPU) | bare+rule / bare_step (CPU) | mj_step µs | rule µs |"
    )
    print("|---" * (len(VARIANTS) + 6) + "|")
    for n in sizes:
        springs = 6 * (n + 1) + 12 * n
        cells = []
        for v in VARIANTS:
            wall = statistics.median(w for w, _ in results[(n, v)])
            cpu = statistics.median(c for _, c in results[(n, v)])
            cells.append(f"{wall:.1f} ({cpu:.1f})")
        cells += [
            f"{statistics.median(ratios[(n, k)]):.2f} "
            f"({min(ratios[(n, k)]):.2f}-{max(ratios[(n, k)]):.2f})"
            for k in ("snakebot", "rule")
        ]
        cells += [f"{costs[n][0]:.0f}", f"{costs[n][1]:.1f}"]
        print(f"| {n} | {4 * (n + 1)} / {springs} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
