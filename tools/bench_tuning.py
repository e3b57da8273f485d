"""Benchmarks and "Done when" checks of the tuning commands (numbers in docs/tuning.md).

    python tools/bench_tuning.py engines [--rounds 5]   evaluations/s: batch, rollout, processes
    python tools/bench_tuning.py grid-vs-cmaes          snake8: 10 x 10 grid vs CMA-ES (100 evals)
    python tools/bench_tuning.py sidewinding            snake12: tuned sidewinding vs the preset
    python tools/bench_tuning.py sysid                  recover perturbed servo parameters
    python tools/bench_tuning.py gains                  snake8: tune gains on the twin
    python tools/bench_tuning.py all

Each candidate runs like `snakebot run --duration 10` (100 Hz control, 2 ms physics). Engines:
  batch       snakebot's engine: mujoco.batch, the runner's cycle in Python (closed loop)
  rollout     mujoco.rollout on controls precomputed per physics step (open loop), stepping only:
              an upper bound for that route, which still lacks the runner's samples
  processes   a process pool, each worker running the normal runner (snakebot.tuning.pool)
"""

from __future__ import annotations

import argparse
import contextlib
import os
import random
import statistics
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.control.cycle import CycleSchedule
from snakebot.gaits import make_gait
from snakebot.tuning.commands import GaitCommands
from snakebot.tuning.engine import TwinBatch
from snakebot.tuning.excitation import chirp_plan, record
from snakebot.tuning.feasibility import Envelope
from snakebot.tuning.gain_search import search_gains
from snakebot.tuning.gains import GainTest
from snakebot.tuning.objectives import objective_for
from snakebot.tuning.pool import PoolJob, ProcessPool
from snakebot.tuning.problem import EvalPlan
from snakebot.tuning.space import build_space, tuning_base
from snakebot.tuning.sysid import ServoFit, fit_servo, load_log
from snakebot.tuning.tuner import tune_gait

DURATION_S = 10.0


def load() -> float:
    """Other processes' load: the 1-minute load average (a rough noise marker)."""
    return os.getloadavg()[0]


def candidates(count: int) -> list[dict[str, float]]:
    rng = np.random.default_rng(0)
    return [
        {"omega": float(rng.uniform(1, 12)), "phase_lag": float(rng.uniform(0.2, 1.4))}
        for _ in range(count)
    ]


def run_batch(robot_name: str, params: list[dict[str, float]], workers: int) -> None:
    robot = load_robot(robot_name)
    batch = TwinBatch(robot, workers=workers)
    gaits = [make_gait("serpenoid", robot.joint_count, p) for p in params]
    envelope = Envelope.for_robot(robot, float(batch.start_com_m[2]))
    batch.run(GaitCommands(gaits, robot), DURATION_S, 100.0, envelope=envelope)


def run_rollout(robot_name: str, params: list[dict[str, float]], workers: int) -> None:
    robot = load_robot(robot_name)
    batch = TwinBatch(robot, workers=workers)
    gaits = [make_gait("serpenoid", robot.joint_count, p) for p in params]
    commands = GaitCommands(gaits, robot)
    cycles = round(DURATION_S * 100)
    schedule = CycleSchedule(100.0, DURATION_S, robot.safety.ramp_s)
    commands.reset(np.zeros((len(gaits), robot.joint_count)), schedule)
    idle = np.zeros((len(gaits), robot.joint_count))
    rows = np.stack([commands(k, k * 0.01, idle)[1] for k in range(cycles)], axis=1)
    steps = batch.twin.steps_for(0.01)
    control = np.repeat(rows, steps, axis=1)  # (B, K*steps, N): zero-order hold
    model, data = batch.model, batch.twin.data
    state = np.empty(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    with rollout.Rollout(nthread=workers) as pool:
        pool.rollout(model, [mujoco.MjData(model) for _ in range(workers)], state, control)


def run_processes(robot_name: str, params: list[dict[str, float]], workers: int) -> None:
    robot = load_robot(robot_name)
    envelope = Envelope.for_robot(robot, 0.023)
    with ProcessPool(workers) as pool:
        pool.run([PoolJob(robot, "serpenoid", p, DURATION_S, 100.0, envelope) for p in params])


def engines(rounds: int, count: int) -> None:
    """Evaluations per second, median (min-max) over rounds run in shuffled order."""
    variants = {
        (name, workers): fn
        for name, fn in (
            ("batch", run_batch),
            ("rollout", run_rollout),
            ("processes", run_processes),
        )
        for workers in (1, 2)
    }
    params = candidates(count)
    results: dict[tuple[str, int], list[float]] = {key: [] for key in variants}
    for robot_name in ("snake8", "snake12"):
        for key in results:
            results[key] = []
        loads = []
        for _ in range(rounds):
            order = list(variants)
            random.shuffle(order)
            for key in order:
                start = time.perf_counter()
                variants[key](robot_name, params, key[1])
                results[key].append(count / (time.perf_counter() - start))
                loads.append(load())
        print(
            f"\n{robot_name}: {count} candidates x {DURATION_S:g} s, {rounds} rounds "
            f"(1-min load average {min(loads):.2f}-{max(loads):.2f})"
        )
        print(f"  {'engine':<10} {'workers':>7} {'evals/s median (min-max)':>28}")
        for (name, workers), values in results.items():
            print(
                f"  {name:<10} {workers:>7} {statistics.median(values):>12.2f} "
                f"({min(values):.2f}-{max(values):.2f})"
            )


def gait_search(
    robot_name: str, gait: str, method: str, budget: int, params: list[str] | None = None
) -> object:
    robot = load_robot(robot_name)
    space = build_space(gait, tuning_base(gait, robot.joint_count, {}), params, joint_limit_rad=1.5)
    return tune_gait(
        robot,
        space,
        objective_for("speed", 0.0, robot.body_length_m),
        method,
        budget=budget,
        seed=0,
        plan=EvalPlan(duration_s=DURATION_S),
    )


def grid_vs_cmaes() -> None:
    grid = gait_search("snake8", "serpenoid", "grid", 100)
    best = grid.best  # type: ignore[attr-defined]
    print(
        f"\nsnake8 grid 10 x 10 omega x phase_lag: best {best.value:.4f} m/s at "
        f"omega {best.params['omega']:.3f}, phase_lag {best.params['phase_lag']:.3f}; "
        f"{len(grid.history)} evaluations in {grid.wall_s:.1f} s"
    )  # type: ignore[attr-defined]
    for seed in (0, 1, 2):
        robot = load_robot("snake8")
        space = build_space("serpenoid", tuning_base("serpenoid", 8, {}))
        cma = tune_gait(
            robot,
            space,
            objective_for("speed", 0.0, robot.body_length_m),
            "cmaes",
            budget=100,
            seed=seed,
            plan=EvalPlan(duration_s=DURATION_S),
        )
        beat = next((e.index + 1 for e in cma.history if e.feasible and e.value > best.value), None)
        print(
            f"  cmaes seed {seed}: best {cma.best.value:.4f} m/s at omega "
            f"{cma.best.params['omega']:.3f}, phase_lag {cma.best.params['phase_lag']:.3f}; "
            f"{len(cma.history)} evaluations in {cma.wall_s:.1f} s; beat the grid at "
            f"evaluation {beat}"
        )


def sidewinding() -> None:
    for budget in (60, 120):
        result = gait_search("snake12", "sidewinding", "cmaes", budget)
        print(
            f"\nsnake12 sidewinding, cmaes budget {budget}: preset "  # type: ignore[attr-defined]
            f"{result.baseline.value:.4f} m/s -> {result.best.value:.4f} m/s "
            f"({len(result.history)} evaluations, {result.wall_s:.1f} s)"
        )
        print(
            "  best params: "
            + ", ".join(
                f"{k}={result.best.params[k]:.3f}"
                for k in (  # type: ignore[attr-defined]
                    "amplitude_even",
                    "amplitude_odd",
                    "spatial_freq_even",
                    "temporal_freq_even",
                    "phase_shift",
                )
            )
        )


def sysid() -> None:
    truth_factors = (1.25, 0.8, 1.5)
    for robot_name, joint, hold in (("snake12", 1, 0.5), ("snake8", 0, 0.0)):
        robot = load_robot(robot_name)
        truth = ServoFit.of(robot).scaled(("stiffness", "damping", "armature"), truth_factors)
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "log.csv"
            with TwinBackend(truth.apply(robot)) as twin:
                start = twin.read_state().position_rad
                record(twin, robot, chirp_plan(robot, start, joint, hold), path)
            began = time.perf_counter()
            result = fit_servo(robot, [load_log(path, robot)])
            wall = time.perf_counter() - began
        errors = {
            field: getattr(result.after, field) / getattr(truth, field) - 1
            for field in ("stiffness_scale", "damping_nms", "armature_kgm2")
        }
        print(
            f"\nsysid {robot_name}, joint {joint} held at {hold} rad and chirped 0.2-6 Hz, "
            f"truth = shipped x {truth_factors}: {wall:.1f} s, {result.simulations} replays, "
            f"twin vs log {result.rms_before_rad:.2e} -> {result.rms_after_rad:.2e} rad RMS"
        )
        print("  relative error: " + ", ".join(f"{k} {v:+.2%}" for k, v in errors.items()))


def gains() -> None:
    robot = load_robot("snake8")
    test = GainTest(joints=tuple(range(robot.joint_count)), gait="serpenoid")
    began = time.perf_counter()
    result = search_gains(lambda: TwinBackend(robot), robot, test, budget=20)
    now, best = result.current, result.best
    print(
        f"\nsnake8 tune gains --backend sim (budget 20, all joints, 6 s serpenoid): "
        f"{time.perf_counter() - began:.1f} s"
    )
    print(
        f"  gait tracking {now.tracking_rms_rad:.4f} rad at P/I/D "
        f"{now.gains.position_p}/{now.gains.position_i}/{now.gains.position_d} -> "
        f"{best.tracking_rms_rad:.4f} rad at {best.gains.position_p}/"
        f"{best.gains.position_i}/{best.gains.position_d}"
    )
    chirp = {j: (result.chirp_before[j][0], result.chirp_after[j][0]) for j in (0, 4, 7)}
    print(
        "  chirp RMS (rad) before -> after: "
        + ", ".join(f"joint {j} {a:.4f} -> {b:.4f}" for j, (a, b) in chirp.items())
    )
    for joint, (a, b) in zip(test.joints, zip(now.steps, best.steps, strict=True), strict=True):
        if joint in (0, 4):
            print(
                f"  joint {joint} step: rise {a.rise_time_s:.3f} -> {b.rise_time_s:.3f} s, "
                f"overshoot {a.overshoot:.1%} -> {b.overshoot:.1%}, steady-state error "
                f"{a.steady_state_error_rad:.4f} -> {b.steady_state_error_rad:.4f} rad"
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "what", choices=("engines", "grid-vs-cmaes", "sidewinding", "sysid", "gains", "all")
    )
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--candidates", type=int, default=8)
    args = parser.parse_args()
    print(f"cores: {os.cpu_count()}, mujoco {mujoco.__version__}, 1-min load {load():.2f}")
    jobs = {
        "engines": lambda: engines(args.rounds, args.candidates),
        "grid-vs-cmaes": grid_vs_cmaes,
        "sidewinding": sidewinding,
        "sysid": sysid,
        "gains": gains,
    }
    for name, job in jobs.items():
        if args.what in (name, "all"):
            with contextlib.suppress(KeyboardInterrupt):
                job()


if __name__ == "__main__":
    main()
