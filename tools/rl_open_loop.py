"""Write a policy folder that always plays one action: an open-loop gait as a "policy", so
`snakebot rl eval` scores it on the same task and seeds as a learned one (docs/learning.md).

    python tools/rl_open_loop.py OUT --env snakebot/SnakeGoal-v0 --encoding dft_shift \
        --action 0,1,0,0,0 [--set KEY=VALUE ...]
    snakebot rl eval OUT --episodes 20
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from snakebot.cli.rl_cmd import parse_settings
from snakebot.config import load_robot
from snakebot.rl.encodings import make_encoding
from snakebot.rl.policy_file import NumpyActor, save_actor, write_settings
from snakebot.rl.settings import (
    GOAL_ENV_ID,
    EnvSettings,
    GoalSettings,
    VelocitySettings,
    settings_dict,
    split_kwargs,
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--env", default=GOAL_ENV_ID)
    parser.add_argument("--encoding", default="dft_shift")
    parser.add_argument("--robot", default="snake8")
    parser.add_argument("--action", required=True, help="comma list in [-1, 1]")
    parser.add_argument("--set", action="append", default=[])
    args = parser.parse_args()
    task = GoalSettings if "Goal" in args.env else VelocitySettings
    kwargs = {"robot": args.robot, "encoding": args.encoding, **parse_settings(args.set)}
    settings = split_kwargs(kwargs, task)
    env: EnvSettings = settings[0]
    robot = load_robot(env.robot)
    encoding = make_encoding(
        env.encoding,
        robot.joint_count,
        robot.lower_rad,
        robot.upper_rad,
        phase_hz=env.phase_hz,
        dft_bins=env.dft_bins,
    )
    action = np.array([float(v) for v in args.action.split(",")])
    if action.shape != (encoding.action_dim,):
        parser.error(f"--action: {env.encoding} takes {encoding.action_dim} numbers")
    phases = 2 * encoding.observed_phases
    n = robot.joint_count
    obs_dim = 2 * n + phases + 2 if "Goal" in args.env else 3 * n + phases + 2
    actor = NumpyActor((np.zeros((1, obs_dim)), np.zeros((action.size, 1))), (np.zeros(1), action))
    args.out.mkdir(parents=True, exist_ok=True)
    save_actor(actor, args.out / "actor.npz")
    write_settings(
        args.out,
        args.env,
        settings_dict(*settings),
        {"algo": "open loop", "action": action.tolist()},
    )
    print(args.out)


if __name__ == "__main__":
    main()
