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
  replay          the snakebot run's own physics bare: its model from its start state, the rest
                  lengths it wrote to ctrl each period, and its compiled stepper (mj_step and
                  Miller's rule in C, friction_c) called once per period as the backend calls
                  it; it ends in the run's state bit for bit (checked). snakebot / replay is
                  what the controller's Python costs and nothing else: the bare_step loops
                  leave out the rule (bare_step) or run it in numpy (bare_step+rule), so they
                  are not the run's physics or not its cost.
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

from snakebot.backends.softbody import SoftBodyBackend, build_body_spec, friction_c
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
VARIANTS = ("snakebot", "snakebot_off", "bare_step", "bare_step+rule", "replay")
STATE = mujoco.mjtState.mjSTATE_INTEGRATION
RATIOS = ("snakebot", "rule", "replay")


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


@dataclasses.dataclass(frozen=True)
class Replay:
    """A snakebot run's physics: the model, the rule, the state the run began and ended in, and
    each period's (ctrl, steps, the stepper's work rows)."""

    model: mujoco.MjModel
    rule: DirectionalFriction
    start: np.ndarray
    periods: list[tuple[np.ndarray, int, tuple[np.ndarray, np.ndarray, np.ndarray]]]
    end: np.ndarray


def state_of(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    state = np.empty(mujoco.mj_stateSize(model, STATE))
    mujoco.mj_getState(model, data, state, STATE)
    return state


def record_replay(body: BodyConfig, seconds: float) -> Replay:
    """The snakebot run once, untimed, keeping what the bare replay needs."""
    gait = make_gait("undulation", body.joint_count)
    metrics = RunMetrics(body.joint_count, body.body_length_m, body.total_mass_kg)
    plan = RunPlan(duration_s=seconds, rate_hz=RATE_HZ, ramp_out=False)
    with SoftBodyBackend(body) as backend:
        model, data, stepper = backend.model, backend.data, backend._stepper
        assert stepper is not None, "the replay needs the compiled stepper (a C compiler)"
        periods = []
        advance = stepper.advance

        def keep(steps: int, *rows: np.ndarray) -> tuple[np.ndarray, float]:
            periods.append((data.ctrl.copy(), steps, rows))
            return advance(steps, *rows)

        stepper.advance = keep  # type: ignore[method-assign]
        start = state_of(model, data)
        run_gait(backend, gait, SafetyLayer.for_robot(body), plan, metrics)
        return Replay(model, backend.friction_rule, start, periods, state_of(model, data))


def run_replay(replay: Replay) -> tuple[float, float, float]:
    """Real-time factors (wall, CPU) of the bare replay, and its end state's largest difference
    from the run's (0: the same physics)."""
    model = replay.model
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, replay.start, STATE)
    mujoco.mj_forward(model, data)
    stepper = friction_c.CompiledStepper(model, data, replay.rule)
    ctrl = data.ctrl
    start, cpu = time.perf_counter(), time.process_time()
    for command, steps, rows in replay.periods:
        ctrl[:] = command
        stepper.advance(steps, *rows)
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    simulated = sum(steps for _, steps, _ in replay.periods) * model.opt.timestep
    off = float(np.abs(state_of(model, data) - replay.end).max())
    return simulated / wall, simulated / cpu, off


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
        bodies, xml, schedules, replays = {}, {}, {}, {}
        mismatch = 0.0
        for n in sizes:
            bodies[n] = body_with(n)
            xml[n] = Path(tmp) / f"soft{n}.xml"
            xml[n].write_text(build_body_spec(bodies[n]).to_xml())
            schedules[n] = ctrl_schedule(bodies[n], args.seconds)
            replays[n] = record_replay(bodies[n], args.seconds)
        # (wall, cpu) real-time factors per block; ratios within a round, on CPU time.
        results: dict[tuple[int, str], list[tuple[float, float]]] = {
            (n, v): [] for n in sizes for v in VARIANTS
        }
        ratios: dict[tuple[int, str], list[float]] = {(n, k): [] for n in sizes for k in RATIOS}
        for _ in range(args.rounds):
            for n in sizes:
                order = list(VARIANTS)
                random.shuffle(order)
                got: dict[str, tuple[float, float]] = {}
                for variant in order:
                    if variant == "replay":
                        wall, cpu, off = run_replay(replays[n])
                        got[variant] = wall, cpu
                        mismatch = max(mismatch, off)
                    elif variant.startswith("snakebot"):
                        got[variant] = run_snakebot(bodies[n], args.seconds, variant == "snakebot")
                    else:
                        got[variant] = run_bare(xml[n], schedules[n], variant.endswith("rule"))
                    results[(n, variant)].append(got[variant])
                ratios[(n, "snakebot")].append(got["snakebot"][1] / got["bare_step"][1])
                ratios[(n, "rule")].append(got["bare_step+rule"][1] / got["bare_step"][1])
                ratios[(n, "replay")].append(got["snakebot"][1] / got["replay"][1])
        costs = {n: micro(xml[n]) for n in sizes}
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"{args.rounds} rounds, {args.seconds:g} s simulated per block, 1 ms steps, control "
        f"{RATE_HZ:g} Hz, pinned to core {args.cpu}, load average {load:.1f}; cells: times real "
        "time by the wall clock (by the process's CPU time); the replay ends "
        f"{mismatch:.3g} from the run's state (0: the same physics)\n"
    )
    print(
        "| segments | points / springs | "
        + " | ".join(VARIANTS)
        + " | snakebot / bare_step (CPU) | bare+rule / bare_step (CPU)"
        " | **snakebot / replay (CPU)** | mj_step µs | rule µs |"
    )
    print("|---" * (len(VARIANTS) + 7) + "|")
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
            for k in RATIOS
        ]
        cells += [f"{costs[n][0]:.0f}", f"{costs[n][1]:.1f}"]
        print(f"| {n} | {4 * (n + 1)} / {springs} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
