"""Benchmark: learning-environment throughput against a bare mj_step loop, and PPO steps/s.

Env vs bare, per encoding, in one process, rounds in shuffled order:
  env    SnakeGoal-v0 env.step() with random actions (gait -> safety -> TwinBackend, the
         observation and the reward), resets included
  bare   the same compiled model, a sinusoid written to ctrl every control period and one
         mj_step(m, d, nstep) per period: the same control decimation, nothing else
  replay the env's own model replaying the ctrl the env sent each control period, from the
         state each stretch began in (the block's start, each reset): the same physics as the
         env's block, bit for bit (its end state is checked), one mj_step(m, d, nstep) per
         period. env/replay is what the env adds and nothing else; bare plays another motion,
         whose contacts cost a different amount per step. Keeping the ctrl costs the env one
         copy per period.
The ratios (goal >= 0.85) are taken within each round; medians over rounds. Both wall
time and process CPU time are reported: CPU time holds on a loaded machine, wall time does not.

PPO: stable-baselines3 PPO (defaults, n_steps = 2048 / n_envs) learning for --ppo-steps on
SnakeGoal-v0 (dft_shift), for each vectorisation (dummy x1, dummy x2, subproc x2): the fastest
is the CLI's default (snakebot/cli/rl_cmd.py DEFAULT_N_ENVS, DEFAULT_VEC).

    python tools/bench_rl.py [--rounds 5] [--steps 200] [--ppo-steps 4096] [--skip-ppo]
                             [--skip-env] [--json]
"""

from __future__ import annotations

import argparse
import json
import random
import statistics
import time
from collections.abc import Callable
from typing import Any

import gymnasium
import mujoco
import numpy as np

import snakebot.rl
from snakebot.rl.train import TrainSettings, train

Clock = Callable[[], float]


STATE = mujoco.mjtState.mjSTATE_INTEGRATION


def state_of(model: Any, data: Any) -> np.ndarray:
    state = np.empty(mujoco.mj_stateSize(model, STATE))
    mujoco.mj_getState(model, data, state, STATE)
    return state


def env_block(
    env: Any, steps: int, rng: np.random.Generator
) -> tuple[float, float, list[tuple[np.ndarray, list[np.ndarray]]], np.ndarray]:
    """Times ``steps`` env steps; also returns the stretches to replay (start state, the ctrl
    of each period) and the state the block ended in."""
    dim = env.action_space.shape[0]
    actions = rng.uniform(-1, 1, (steps, dim)).astype(np.float32)
    backend = env.loop.backend
    model, data = backend.model, backend.data
    stretches = [(state_of(model, data), [])]
    sent = stretches[0][1]
    period = getattr(backend, "_period", None)  # the twin's compiled period (period_c)
    if period is not None:
        stepping = period.advance

        def keep_and_step(steps: int, scan: bool) -> np.ndarray:
            sent.append(data.ctrl.copy())
            result: np.ndarray = stepping(steps, scan)
            return result

        period.advance = keep_and_step
    else:  # a tree from before period_c (PYTHONPATH=<other tree>): its work stepper
        integrating = backend.__class__._step_integrating

        def keep_integrating(steps: int) -> np.ndarray:
            sent.append(data.ctrl.copy())
            result: np.ndarray = integrating(backend, steps)
            return result

        backend._step_integrating = keep_integrating
    wall, cpu = time.perf_counter(), time.process_time()
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
            sent = []
            stretches.append((state_of(model, data), sent))
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    if period is not None:
        del period.advance
    else:
        del backend._step_integrating
    return wall, cpu, stretches, state_of(model, data)


def replay_block(
    model: Any, nstep: int, stretches: list[tuple[np.ndarray, list[np.ndarray]]], end: np.ndarray
) -> tuple[float, float, float]:
    """The env block's physics bare; returns wall and CPU seconds and the largest difference of
    the end state from the env's (0: the same physics)."""
    data = mujoco.MjData(model)
    ctrl = data.ctrl
    wall = cpu = 0.0
    for start, sent in stretches:
        mujoco.mj_setState(model, data, start, STATE)
        mujoco.mj_forward(model, data)
        w, c = time.perf_counter(), time.process_time()
        for command in sent:
            ctrl[:] = command
            mujoco.mj_step(model, data, nstep)
        wall, cpu = wall + time.perf_counter() - w, cpu + time.process_time() - c
    return wall, cpu, float(np.abs(state_of(model, data) - end).max())


def bare_block(
    model: Any, cycles_per_step: int, nstep: int, steps: int, joints: int
) -> tuple[float, float]:
    data = mujoco.MjData(model)
    lags = 0.7 * np.arange(joints)
    dt = nstep * model.opt.timestep
    wall, cpu = time.perf_counter(), time.process_time()
    t = 0.0
    for _ in range(steps * cycles_per_step):
        data.ctrl[:] = 0.5 * np.sin(2 * np.pi * 0.8 * t - lags)
        mujoco.mj_step(model, data, nstep)
        t += dt
    return time.perf_counter() - wall, time.process_time() - cpu


def bench_envs(rounds: int, steps: int, encodings: list[str]) -> dict[str, Any]:
    rng = np.random.default_rng(0)
    envs = {e: gymnasium.make(snakebot.rl.GOAL_ENV_ID, encoding=e).unwrapped for e in encodings}
    for env in envs.values():
        env.reset(seed=0)
    any_env = next(iter(envs.values()))
    model = any_env.loop.backend.model
    cycles = any_env.settings.cycles_per_action
    nstep = any_env.loop.backend.steps_for(any_env.loop.dt_s)
    joints = any_env.robot.joint_count
    rows: dict[str, dict[str, list[float]]] = {
        e: {
            "env": [],
            "bare": [],
            "ratio_wall": [],
            "ratio_cpu": [],
            "replay_ratio_wall": [],
            "replay_ratio_cpu": [],
            "env_cpu_ms": [],
        }
        for e in encodings
    }
    mismatch = 0.0
    for _ in range(rounds):
        order = list(encodings)
        random.shuffle(order)
        for encoding in order:
            env_wall, env_cpu, stretches, end = env_block(envs[encoding], steps, rng)
            first = [replay_block, bare_block]
            random.shuffle(first)
            for block in first:
                if block is replay_block:
                    replay_wall, replay_cpu, off = replay_block(model, nstep, stretches, end)
                    mismatch = max(mismatch, off)
                else:
                    bare_wall, bare_cpu = bare_block(model, cycles, nstep, steps, joints)
            row = rows[encoding]
            row["replay_ratio_wall"].append(replay_wall / env_wall)
            row["replay_ratio_cpu"].append(replay_cpu / env_cpu)
            row["env"].append(steps / env_wall)
            row["bare"].append(steps / bare_wall)
            row["ratio_wall"].append(bare_wall / env_wall)
            row["ratio_cpu"].append(bare_cpu / env_cpu)
            row["env_cpu_ms"].append(1000 * env_cpu / steps)
    for env in envs.values():
        env.close()
    return {
        e: {key: round(statistics.median(values), 3) for key, values in row.items()}
        | {
            "physics_steps_per_env_step": cycles * nstep,
            "replay_ratio_cpu_range": [min(row["replay_ratio_cpu"]), max(row["replay_ratio_cpu"])],
            "replay_end_state_difference": mismatch,
        }
        for e, row in rows.items()
    }


def bench_ppo(ppo_steps: int) -> dict[str, Any]:
    import tempfile
    from pathlib import Path

    out: dict[str, Any] = {}
    for n_envs, vec in ((1, "dummy"), (2, "dummy"), (2, "subproc")):
        settings = TrainSettings(
            snakebot.rl.GOAL_ENV_ID, {"encoding": "dft_shift"}, ppo_steps, n_envs, vec
        )
        with tempfile.TemporaryDirectory() as folder:
            result = train(settings, Path(folder), progress=None, plot=False)
        out[f"{vec}x{n_envs}"] = {
            "steps_per_s": round(result.steps_per_s, 1),
            "cpu_s": round(result.cpu_s, 1),
            "wall_s": round(result.wall_s, 1),
        }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--steps", type=int, default=200, help="env steps per block")
    parser.add_argument("--encodings", default=",".join(snakebot.rl.ENCODINGS))
    parser.add_argument("--ppo-steps", type=int, default=4096)
    parser.add_argument("--skip-ppo", action="store_true")
    parser.add_argument("--skip-env", action="store_true")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    result: dict[str, Any] = {"env_vs_bare": {}}
    if not args.skip_env:
        result["env_vs_bare"] = bench_envs(args.rounds, args.steps, args.encodings.split(","))
    if not args.skip_ppo:
        result["ppo"] = bench_ppo(args.ppo_steps)
    if args.json:
        print(json.dumps(result, indent=2))
        return
    print(
        f"{'encoding':10s} {'env/s':>8s} {'bare/s':>8s} {'ratio wall':>11s} {'ratio cpu':>10s} "
        f"{'CPU ms/step':>12s} {'replay cpu':>11s} {'(min-max)':>11s}"
    )
    for encoding, row in result["env_vs_bare"].items():
        print(
            f"{encoding:10s} {row['env']:8.0f} {row['bare']:8.0f} {row['ratio_wall']:11.2f} "
            f"{row['ratio_cpu']:10.2f} {row['env_cpu_ms']:12.2f} {row['replay_ratio_cpu']:11.2f} "
            f"{row['replay_ratio_cpu_range'][0]:.2f}-{row['replay_ratio_cpu_range'][1]:.2f}"
        )
    if result["env_vs_bare"]:
        off = max(row["replay_end_state_difference"] for row in result["env_vs_bare"].values())
        print(f"replay vs env end states: largest difference {off:.3g} (0 = the same physics)")
    for name, row in result.get("ppo", {}).items():
        print(
            f"PPO {name:10s} {row['steps_per_s']:7.1f} steps/s ({row['cpu_s']} CPU s, "
            f"{row['wall_s']} s wall)"
        )


if __name__ == "__main__":
    main()
