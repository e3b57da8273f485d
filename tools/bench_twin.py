"""Benchmark: simulated steps per second of `snakebot run --backend sim` vs bare mj_step loops.

For 8, 16 and 32 servos, each round runs, back to back in one process and in shuffled order:
  snakebot       the runner path of `snakebot run` (gait -> safety -> TwinBackend, metrics)
  facade         the same through snakebot.connect(robot).run(...), what a script calls
  snakebot+log   the same with the per-cycle CSV telemetry log
  bare_step      the exported MJCF, numpy ctrl every 10 ms, one mj_step() call per physics step
  bare_nstep     the same, one mj_step(m, d, nstep) call per control period
  bare_replay    the twin's own compiled model from the twin's start state, replaying the ctrl
                 sequence the snakebot run sent, one mj_step() call per physics step: the same
                 physics as the run (checked: it ends in the run's state), so snakebot /
                 bare_replay is what the controller costs and nothing else. bare_step plays
                 another motion (an instant 0.5 Hz sine against the run's ramped serpenoid),
                 whose contacts cost a different amount per step.
Ratios are taken within each round, then the median over rounds is reported. ``--clock cpu``
times each block by the thread's CPU time instead of the wall clock (on a loaded machine the
time spent waiting for a core then does not count).

    python tools/bench_twin.py [--rounds 7] [--seconds 5] [--sizes 8,16,32] [--clock wall]
"""

from __future__ import annotations

import argparse
import dataclasses
import random
import statistics
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np

import snakebot
from snakebot.backends.twin import TwinBackend, build_spec
from snakebot.backends.twin.model_builder import add_actuators
from snakebot.config import RobotConfig, load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from snakebot.telemetry import CsvTelemetryWriter

RATE_HZ = 100.0
CLOCKS = {"wall": time.perf_counter, "cpu": time.thread_time}
now = CLOCKS["wall"]
RATIOS = ("step", "facade_step", "nstep", "log_step", "replay", "log_replay")


def robot_with(joints: int) -> RobotConfig:
    base = load_robot("snake8")
    chain = tuple(dataclasses.replace(base.joints[0], servo_id=i + 1) for i in range(joints))
    return dataclasses.replace(base, joints=chain)


def run_snakebot(robot: RobotConfig, seconds: float, log_dir: Path | None) -> float:
    backend = TwinBackend(robot)
    gait = make_gait("serpenoid", robot.joint_count)
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    plan = RunPlan(duration_s=seconds, rate_hz=RATE_HZ, ramp_out=False)
    with backend:
        log = CsvTelemetryWriter(log_dir / "bench.csv", robot.joint_count) if log_dir else None
        start = now()
        run_gait(backend, gait, SafetyLayer.for_robot(robot), plan, metrics, log=log)
        wall = now() - start
        if log:
            log.close()
        steps = round(seconds / backend.model.opt.timestep)
    return steps / wall


def run_facade(robot: RobotConfig, seconds: float) -> float:
    with snakebot.connect(robot, backend="twin") as snake:
        start = now()
        snake.run("serpenoid", duration_s=seconds, rate_hz=RATE_HZ, ramp_out=False)
        wall = now() - start
        steps = round(seconds / snake.backend.model.opt.timestep)  # type: ignore[attr-defined]
    return steps / wall


@dataclasses.dataclass(frozen=True)
class Replay:
    """A snakebot run's physics, to replay bare: the twin's model, its state when the run began,
    the ctrl (C, N) sent each control period, and the state the run ended in."""

    model: mujoco.MjModel
    start_state: np.ndarray
    ctrl: np.ndarray
    end_state: np.ndarray
    steps_per_cycle: int


def record_replay(robot: RobotConfig, seconds: float) -> Replay:
    """Run the snakebot path once, untimed, keeping what a bare loop needs to replay it."""
    backend = TwinBackend(robot)
    gait = make_gait("serpenoid", robot.joint_count)
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    plan = RunPlan(duration_s=seconds, rate_hz=RATE_HZ, ramp_out=False)
    what = mujoco.mjtState.mjSTATE_INTEGRATION
    with backend:
        model, data = backend.model, backend.data
        sent: list[np.ndarray] = []
        period = getattr(backend, "_period", None)  # the compiled period (period_c)
        if period is not None:
            stepping = period.advance

            def step_and_keep(steps: int, scan: bool) -> np.ndarray:
                sent.append(data.ctrl.copy())
                return stepping(steps, scan)

            period.advance = step_and_keep  # type: ignore[method-assign]
        else:  # a tree from before period_c (PYTHONPATH=<other tree>): its work stepper
            integrating = backend._step_integrating

            def keep_integrating(steps: int) -> np.ndarray:
                sent.append(data.ctrl.copy())
                return integrating(steps)

            backend._step_integrating = keep_integrating  # type: ignore[method-assign]
        start = np.empty(mujoco.mj_stateSize(model, what))
        mujoco.mj_getState(model, data, start, what)
        run_gait(backend, gait, SafetyLayer.for_robot(robot), plan, metrics)
        end = np.empty_like(start)
        mujoco.mj_getState(model, data, end, what)
        steps = backend.steps_for(1.0 / RATE_HZ)
    return Replay(model, start, np.array(sent), end, steps)


def run_replay(replay: Replay) -> tuple[float, float]:
    """Steps per second of the bare replay, and its largest difference from the run's end state."""
    model = replay.model
    data = mujoco.MjData(model)
    what = mujoco.mjtState.mjSTATE_INTEGRATION
    mujoco.mj_setState(model, data, replay.start_state, what)
    mujoco.mj_forward(model, data)
    per_cycle = replay.steps_per_cycle
    ctrl = data.ctrl
    start = now()
    for command in replay.ctrl:
        ctrl[:] = command
        for _ in range(per_cycle):
            mujoco.mj_step(model, data)
    wall = now() - start
    end = np.empty_like(replay.end_state)
    mujoco.mj_getState(model, data, end, what)
    return len(replay.ctrl) * per_cycle / wall, float(np.abs(end - replay.end_state).max())


def run_bare(xml_path: Path, joints: int, seconds: float, nstep_call: bool) -> float:
    model = mujoco.MjModel.from_xml_path(str(xml_path))
    data = mujoco.MjData(model)
    per_cycle = round(1.0 / RATE_HZ / model.opt.timestep)
    cycles = round(seconds * RATE_HZ)
    phase = 0.7 * np.arange(joints)
    start = now()
    for k in range(cycles):
        data.ctrl[:] = 0.4 * np.sin(np.pi * k / RATE_HZ - phase)
        if nstep_call:
            mujoco.mj_step(model, data, per_cycle)
        else:
            for _ in range(per_cycle):
                mujoco.mj_step(model, data)
    wall = now() - start
    return cycles * per_cycle / wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--seconds", type=float, default=5.0, help="simulated seconds per block")
    parser.add_argument("--sizes", default="8,16,32")
    parser.add_argument(
        "--clock",
        choices=tuple(CLOCKS),
        default="wall",
        help="wall (the default) or cpu: this thread's CPU time, which holds on a loaded machine",
    )
    args = parser.parse_args()
    global now
    now = CLOCKS[args.clock]
    sizes = [int(s) for s in args.sizes.split(",")]
    variants = ["snakebot", "facade", "snakebot+log", "bare_step", "bare_nstep", "bare_replay"]
    with tempfile.TemporaryDirectory() as tmp:
        tmp_path = Path(tmp)
        robots, xml, replays = {}, {}, {}
        mismatch = 0.0
        for n in sizes:
            robots[n] = robot_with(n)
            replays[n] = record_replay(robots[n], args.seconds)
            spec = build_spec(robots[n])
            add_actuators(spec, robots[n])
            spec.compile()
            xml[n] = tmp_path / f"snake{n}.xml"
            xml[n].write_text(spec.to_xml())
        results: dict[tuple[int, str], list[float]] = {(n, v): [] for n in sizes for v in variants}
        ratios: dict[tuple[int, str], list[float]] = {(n, v): [] for n in sizes for v in RATIOS}
        for _ in range(args.rounds):
            for n in sizes:
                order = variants[:]
                random.shuffle(order)
                got: dict[str, float] = {}
                for variant in order:
                    if variant == "snakebot":
                        got[variant] = run_snakebot(robots[n], args.seconds, None)
                    elif variant == "facade":
                        got[variant] = run_facade(robots[n], args.seconds)
                    elif variant == "snakebot+log":
                        got[variant] = run_snakebot(robots[n], args.seconds, tmp_path)
                    elif variant == "bare_replay":
                        got[variant], off = run_replay(replays[n])
                        mismatch = max(mismatch, off)
                    else:
                        got[variant] = run_bare(
                            xml[n], n, args.seconds, nstep_call=variant == "bare_nstep"
                        )
                    results[(n, variant)].append(got[variant])
                ratios[(n, "step")].append(got["snakebot"] / got["bare_step"])
                ratios[(n, "facade_step")].append(got["facade"] / got["bare_step"])
                ratios[(n, "nstep")].append(got["snakebot"] / got["bare_nstep"])
                ratios[(n, "log_step")].append(got["snakebot+log"] / got["bare_step"])
                ratios[(n, "replay")].append(got["snakebot"] / got["bare_replay"])
                ratios[(n, "log_replay")].append(got["snakebot+log"] / got["bare_replay"])

    print(
        f"{args.rounds} rounds, {args.seconds:g} s simulated per block, control {RATE_HZ:g} Hz, "
        f"{args.clock} clock; the bare replay ends {mismatch:.3g} from the run's state (largest "
        "difference of any state variable: 0 = the same physics, bit for bit)\n"
    )
    print(
        "| servos | "
        + " | ".join(f"{v} steps/s" for v in variants)
        + " | snakebot / bare_step | facade / bare_step | snakebot / bare_nstep"
        " | snakebot+log / bare_step | **snakebot / bare_replay** | snakebot+log / bare_replay |"
    )
    print("|---" * (len(variants) + 1 + len(RATIOS)) + "|")
    for n in sizes:
        cells = [f"{statistics.median(results[(n, v)]):,.0f}" for v in variants]
        cells += [
            f"{statistics.median(ratios[(n, k)]):.2f} "
            f"({min(ratios[(n, k)]):.2f}-{max(ratios[(n, k)]):.2f})"
            for k in RATIOS
        ]
        print(f"| {n} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
