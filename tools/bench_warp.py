"""The Warp engine's speed: B candidates x D s of a robot's gait in one batch, on a Warp device.

The issue's goal: 10^4 candidates x 8 s of snake12 in under a minute on one H100/H200-class GPU
(MJX, measured earlier: 4,096 x 8 s in 97 s after 157 s of compilation). Run it on the GPU:

    python tools/bench_warp.py --device cuda --count 10000 --duration 8 --workers 16

It reports, each timed apart: building the device model; a first short batch (kernel
compilation and loading, the CUDA graph capture); the timed batch through the whole engine
(WarpGaitProblem.evaluate: host gait tables and safety layer, device physics and metrics,
scores); and the host-only part (the gait tables and safety layer alone), so the device's share
is the difference. On a machine without a GPU it runs on Warp's CPU device (use a tiny --count
and --duration there): that is not the GPU figure, and the output says so.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

from snakebot.config import load_robot
from snakebot.control.cycle import CycleSchedule
from snakebot.tuning.commands import GaitCommands
from snakebot.tuning.engine_warp import TABLE_CYCLES, WarpGaitProblem, require_warp, tabled_gaits
from snakebot.tuning.objectives import objective_for
from snakebot.tuning.problem import EvalPlan
from snakebot.tuning.space import build_space, tuning_base

GOAL_S = 60.0


def host_only_s(problem: WarpGaitProblem, params: list[dict[str, object]], rate_hz: float) -> float:
    """Seconds to make every cycle's targets and commands on the host, no device involved."""
    robot, batch = problem.robot, problem._warp
    gaits = [problem.gait(p) for p in params]  # type: ignore[arg-type]
    commands = GaitCommands(gaits, robot)
    start = time.perf_counter()
    schedule = CycleSchedule(
        rate_hz,
        problem.plan.duration_s,
        robot.safety.ramp_s,
        ramp_out=False,
        timestep_s=float(batch.twin.model.opt.timestep),
    )
    times = schedule.cycle_times(commands.length)
    measured = np.zeros((len(gaits), robot.joint_count))
    commands.reset(measured, schedule)
    table = tabled_gaits(commands)
    for k in range(0, len(times) - 1, TABLE_CYCLES):
        span = range(k, min(k + TABLE_CYCLES, len(times) - 1))
        batch.command_rows(commands, table, span, times, measured)
    return time.perf_counter() - start


def main() -> None:
    """Build, warm up, time one batch and print (and --json) the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="snake12")
    parser.add_argument("--gait", default="sidewinding")
    parser.add_argument("--count", type=int, default=10_000)
    parser.add_argument("--duration", type=float, default=8.0)
    parser.add_argument("--rate", type=float, default=100.0)
    parser.add_argument("--device", default="cuda")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", type=Path)
    parser.add_argument(
        "--host-only",
        action="store_true",
        help="time only the host's gait tables and safety layer for --count x --duration",
    )
    args = parser.parse_args()
    wp, _ = require_warp()
    robot = load_robot(args.robot)
    base = tuning_base(args.gait, robot.joint_count, {})
    limit = float(min(-robot.lower_rad.max(), robot.upper_rad.min()))
    space = build_space(args.gait, base, None, {}, limit)
    objective = objective_for("speed", 0.0, robot.body_length_m)
    rng = np.random.default_rng(args.seed)
    low = np.array([d.lower for d in space.dims])
    high = np.array([d.upper for d in space.dims])
    points = [low + (high - low) * rng.random(len(low)) for _ in range(args.count)]
    params = [space.params(tuple(float(v) for v in p)) for p in points]

    def plan(duration_s: float) -> EvalPlan:
        return EvalPlan(
            duration_s=duration_s,
            rate_hz=args.rate,
            workers=args.workers,
            engine="warp",
            device=args.device,
        )

    start = time.perf_counter()
    problem = WarpGaitProblem(robot, space, objective, plan(args.duration))
    build_s = time.perf_counter() - start
    if args.host_only:
        host_s = host_only_s(problem, params, args.rate)  # type: ignore[arg-type]
        print(f"host commands for {args.count} x {args.duration:g} s: {host_s:.3g} s")
        return
    warm = WarpGaitProblem(robot, space, objective, plan(0.1))
    start = time.perf_counter()
    warm.evaluate(points)
    first_s = time.perf_counter() - start
    start = time.perf_counter()
    evaluations = problem.evaluate(points)
    wp.synchronize()
    timed_s = time.perf_counter() - start
    host_s = host_only_s(problem, params, args.rate)  # type: ignore[arg-type]
    device = wp.get_device(args.device)
    steps = round(args.duration / float(problem._twin.model.opt.timestep))
    result = {
        "robot": args.robot,
        "gait": args.gait,
        "count": args.count,
        "duration_s": args.duration,
        "device": args.device,
        "device_name": str(device.name),
        "is_gpu": bool(device.is_cuda),
        "workers": args.workers,
        "build_s": build_s,
        "first_batch_s": first_s,
        "timed_batch_s": timed_s,
        "host_commands_s": host_s,
        "candidates_per_s": args.count / timed_s,
        "world_steps_per_s": args.count * steps / timed_s,
        "feasible": sum(e.feasible for e in evaluations),
    }
    for key, value in result.items():
        print(f"{key}: {value:.4g}" if isinstance(value, float) else f"{key}: {value}")
    goal = args.count >= 10_000 and args.duration >= 8.0 and args.robot == "snake12"
    if not device.is_cuda:
        print("not a GPU (Warp's CPU device): this is not the GPU figure")
    elif goal:
        verdict = "met" if timed_s < GOAL_S else "NOT met"
        print(f"goal (10^4 x 8 s of snake12 under {GOAL_S:g} s): {verdict}")
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
