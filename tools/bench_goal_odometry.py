"""A goal policy driven through the odometry against the same policy on ground truth.

For each seed the goal is the one ``SnakeGoal-v0`` draws for it (``rl eval``'s goals: 2-4 body
lengths from the centre of mass, any bearing). The policy plays it twice on the twin through
``run_gait`` at the env's control rate, as ``snakebot run --policy DIR --command X,Y`` does,
once with its pose from the
twin (ground truth) and once from ``ChassisOdometry`` (``--odometry``: the measured joints and
the head IMU). As in the env, the referee sees the truth: the episode ends, reached, when the
TRUE centre of mass comes within the task's goal radius, else at its time limit. A stricter
column stops where the pose source itself first says "within the radius" and asks whether the
true centre of mass is then within it (on the truth the two are the same).

    python tools/bench_goal_odometry.py goal/                      # seeds 1000-1019 (rl eval's)
    python tools/bench_goal_odometry.py goal/ --seeds 1000:1005 --json
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from snakebot.backends.twin import TwinBackend
from snakebot.cli.goto_options import odometry_for
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.rl.policy_file import PolicyFile, load_policy
from snakebot.rl.policy_gait import PolicyGait, state_reader
from snakebot.rl.settings import GoalSettings, split_kwargs
from snakebot.types import BodyState


def drawn_goal(policy: PolicyFile, seed: int) -> tuple[float, float]:
    """The goal the policy's SnakeGoal env draws on ``reset(seed=seed)``, from the centre of
    mass at the start (m, world = the head's frame at the twin's straight start)."""
    import gymnasium

    import snakebot.rl  # noqa: F401  (registers the environments)

    env = gymnasium.make(policy.env_id, **dict(policy.env_kwargs))
    try:
        _, info = env.reset(seed=seed)
        com = env.unwrapped.loop.body().com_m[:2]  # type: ignore[attr-defined]
        goal = np.asarray(info["goal_xy_m"]) - com
    finally:
        env.close()
    return float(goal[0]), float(goal[1])


def play(
    policy: PolicyFile, goal: tuple[float, float], odometry: bool, own_stop: bool = False
) -> dict[str, object]:
    """One episode: the policy to ``goal`` with the twin's pose or the odometry's. It ends when
    the true centre of mass is within the goal radius, or (``own_stop``) when the pose source
    says so; ``reached``: the true centre of mass is within the radius then."""
    settings, task = split_kwargs(dict(policy.env_kwargs), GoalSettings)
    assert isinstance(task, GoalSettings)
    robot = load_robot(settings.robot)
    radius_m = task.goal_radius_bl * robot.body_length_m
    limit_s = settings.episode_s
    estimate = odometry_for(robot)
    with TwinBackend(robot) as twin:
        estimate.start(twin.read_state())
        pose = estimate if odometry else twin
        gait = PolicyGait(policy, robot, state_reader(twin), goal, pose=pose)
        misses: list[float] = []  # the true miss when the run stopped

        def at_goal() -> str | None:
            body: BodyState | None = pose.body_state()
            if body is None or gait.goal_xy_m is None:
                return None
            judged = body.com_m[:2] if own_stop else twin.body_state().com_m[:2]
            if math.dist(judged, gait.goal_xy_m) > radius_m:
                return None
            misses.append(math.dist(twin.body_state().com_m[:2], gait.goal_xy_m))
            return "reached"

        metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
        result = run_gait(
            twin,
            gait,
            SafetyLayer.for_robot(robot),
            RunPlan(limit_s, settings.control_hz, ramp_out=False),
            metrics,
            observers=[estimate],
            stop=at_goal,
        )
        return {
            "reached": bool(misses) and misses[0] <= radius_m,
            "time_s": float(result.summary["duration_s"]),  # type: ignore[arg-type]
            "true_miss_m": misses[0] if misses else None,
            "stopped": result.stopped_by,
        }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("policy", type=Path, help="a SnakeGoal policy folder (rl train --out)")
    parser.add_argument("--seeds", default="1000:1020", help="first:stop (default rl eval's)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    policy = load_policy(args.policy)
    first, stop = (int(v) for v in args.seeds.split(":"))
    rows = []
    for seed in range(first, stop):
        began = time.perf_counter()
        goal = drawn_goal(policy, seed)
        truth = play(policy, goal, odometry=False)
        odo = play(policy, goal, odometry=True)
        odo_own = play(policy, goal, odometry=True, own_stop=True)
        rows.append(
            {"seed": seed, "goal_m": goal, "truth": truth, "odometry": odo, "own_stop": odo_own}
        )
        if not args.json:
            print(
                f"| {seed} | {goal[0]:.2f}, {goal[1]:.2f} "
                f"| {'yes' if truth['reached'] else 'no'} | {truth['time_s']:.1f} s "
                f"| {'yes' if odo['reached'] else 'no'} | {odo['time_s']:.1f} s "
                f"| {'yes' if odo_own['reached'] else 'no'} ({odo_own['true_miss_m'] or 0:.2f} m) "
                f"| {time.perf_counter() - began:.0f} s |",
                flush=True,
            )
    with_truth = sum(bool(r["truth"]["reached"]) for r in rows)  # type: ignore[index]
    with_odometry = sum(bool(r["odometry"]["reached"]) for r in rows)  # type: ignore[index]
    both = sum(
        bool(r["truth"]["reached"]) and bool(r["odometry"]["reached"])  # type: ignore[index]
        for r in rows
    )
    own = sum(bool(r["own_stop"]["reached"]) for r in rows)  # type: ignore[index]
    totals = {
        "goals": len(rows),
        "reached_with_truth": with_truth,
        "reached_with_odometry": with_odometry,
        "reached_with_both": both,
        "ratio": with_odometry / with_truth if with_truth else None,
        "reached_with_odometry_own_stop": own,
    }
    if args.json:
        print(json.dumps({"policy": str(args.policy), "rows": rows, **totals}, indent=1))
    else:
        print(json.dumps(totals))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
