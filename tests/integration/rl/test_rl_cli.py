"""`snakebot rl train/eval/compare` as a user runs them: the CI's 2 x 2048-step PPO smoke."""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

import gymnasium
import numpy as np
import pytest

import snakebot.rl
from snakebot.rl.policy_file import CHECKPOINT_DIR, checkpoint_name, load_policy
from tests.integration.rl.policies import constant_policy

pytestmark = pytest.mark.slow
# Cheaper steps for CI (25 Hz actions, one control cycle each); the PPO run is the real one.
FAST = ["--set", "action_hz=25", "--set", "control_hz=25", "--set", "episode_s=8"]


def cli(*args: str, timeout: float = 900) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "snakebot", *args], capture_output=True, text=True, timeout=timeout
    )


def test_ppo_smoke_trains_two_rollouts_saves_the_policy_and_evaluates_it(tmp_path: Path) -> None:
    out = tmp_path / "policy"
    done = cli(
        "rl",
        "train",
        "--env",
        "snakebot/SnakeGoal-v0",
        "--encoding",
        "dft_shift",
        "--steps",
        "4096",
        "--n-envs",
        "2",
        "--vec",
        "dummy",
        "--out",
        str(out),
        *FAST,
    )
    assert done.returncode == 0, done.stderr
    assert "2048/4096 steps" in done.stderr and "4096/4096 steps" in done.stderr  # progress
    with (out / "learning_curve.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [int(r["steps"]) for r in rows] == [2048, 4096]
    assert all(float(r["episodes"]) > 0 and np.isfinite(float(r["mean_return"])) for r in rows)
    assert (out / "learning_curve.png").stat().st_size > 10_000
    policy = load_policy(out)
    assert policy.env_kwargs["encoding"] == "dft_shift"
    assert policy.env_kwargs["action_hz"] == 25 and policy.env_kwargs["goal_bonus"] == 10.0
    assert policy.meta["steps"] == 4096 and policy.meta["cpu_s"] > 0  # dummy: CPU counted

    # The numpy actor is SB3's deterministic policy.
    from stable_baselines3 import PPO

    model = PPO.load(out / "policy.zip", device="cpu")
    env = gymnasium.make(snakebot.rl.GOAL_ENV_ID, **policy.env_kwargs)
    obs, _ = env.reset(seed=5)
    for _ in range(5):
        expected, _ = model.predict(obs, deterministic=True)
        np.testing.assert_allclose(policy.actor(obs), expected, atol=1e-5)
        obs, *_ = env.step(expected)
    env.close()

    evaluated = cli("rl", "eval", str(out), "--episodes", "2", "--json")
    assert evaluated.returncode == 0, evaluated.stderr
    results = json.loads(evaluated.stdout)
    assert set(results) == {"policy", "zero", "random", "bearing", "steered"}
    assert all(r["episodes"] == 2 for r in results.values())


def dft_shift_goal_policy(
    folder: Path, action: list[float], bearing_rad: tuple[float, float]
) -> Path:
    """A constant dft_shift goal policy for snake8: 12 s episodes, goals 2-2.5 body lengths away
    at ``bearing_rad`` (low, high) from the start heading."""
    return constant_policy(
        folder,
        snakebot.rl.GOAL_ENV_ID,
        action,
        2 * 8 + 2 + 2,
        encoding="dft_shift",
        episode_s=12,
        goal_bearing_rad=bearing_rad,
        goal_distance_bl=(2.0, 2.5),
    )


def test_eval_counts_goals_reached_against_zero_and_random(tmp_path: Path) -> None:
    # A policy that always swims ahead, on goals straight ahead: it reaches them all; a zero
    # dft_shift action holds the snake straight and still.
    folder = dft_shift_goal_policy(tmp_path / "ahead", [0, 1, 0, 0, 0], (0.0, 0.0))
    video = tmp_path / "first.mp4"
    done = cli("rl", "eval", str(folder), "--episodes", "3", "--json", "--video", str(video))
    assert done.returncode == 0, done.stderr
    results = json.loads(done.stdout)
    assert results["policy"]["success_rate"] == 1.0
    assert results["policy"]["time_to_goal_s"] < 12
    assert results["zero"]["success_rate"] == 0.0
    assert results["policy"]["cost_of_transport"] > 0
    assert video.stat().st_size > 1000


def test_eval_sets_the_policy_beside_serpenoids_steered_toward_the_goal(tmp_path: Path) -> None:
    # Goals to the side (0.6-1.2 rad off the head's heading): a policy holding one pose (the
    # zero dft_shift action) gets nowhere; the bearing rule turns a serpenoid toward each goal,
    # on the same seeds and so the same goals.
    folder = dft_shift_goal_policy(tmp_path / "still", [0, 0, 0, 0, 0], (0.6, 1.2))
    done = cli("rl", "eval", str(folder), "--episodes", "3", "--json")
    assert done.returncode == 0, done.stderr
    results = json.loads(done.stdout)
    assert set(results) == {"policy", "zero", "random", "bearing", "steered"}
    assert results["policy"]["success_rate"] == 0.0
    bearing = results["bearing"]
    assert bearing["success_rate"] == 1.0 and bearing["time_to_goal_s"] < 12
    assert bearing["path_efficiency"] > 0.3
    assert bearing["cost_of_transport"] > 0
    table = cli("rl", "eval", str(folder), "--episodes", "1")
    assert table.returncode == 0, table.stderr
    assert "path eff" in table.stdout and "bearing" in table.stdout and "steered" in table.stdout


def test_eval_of_training_seeds_shows_one_row_with_intervals_over_them(tmp_path: Path) -> None:
    # Two policies of one configuration (as rl compare --seeds writes them): one swims ahead,
    # one holds still, on goals straight ahead; the row is their mean (50 % of goals) with a t
    # interval over the two, each one's own figures kept under "policies".
    ahead = dft_shift_goal_policy(tmp_path / "seed-0", [0, 1, 0, 0, 0], (0.0, 0.0))
    still = dft_shift_goal_policy(tmp_path / "seed-1", [0, 0, 0, 0, 0], (0.0, 0.0))
    done = cli("rl", "eval", str(ahead), str(still), "--episodes", "2", "--json")
    assert done.returncode == 0, done.stderr
    results = json.loads(done.stdout)
    policy = results["policy"]
    assert policy["training_seeds"] == 2 and policy["success_rate"] == 0.5
    low, high = policy["interval95"]["success_rate"]
    assert low < 0.0 and high > 1.0  # two seeds this far apart: t(0.975, 1) = 12.7
    assert [p["success_rate"] for p in policy["policies"]] == [1.0, 0.0]
    assert results["bearing"]["interval_over"] == "episodes"
    other = dft_shift_goal_policy(tmp_path / "far", [0, 1, 0, 0, 0], (0.6, 1.2))
    mixed = cli("rl", "eval", str(ahead), str(other), "--episodes", "1")
    assert mixed.returncode == 1
    assert "goal_bearing_rad" in mixed.stderr and str(other) in mixed.stderr


def with_checkpoints(folder: Path, actions: dict[int, list[float]]) -> Path:
    """Actor snapshots as training keeps them (checkpoints/actor-STEPS.npz), each a constant
    action, beside the folder's own actor."""
    snapshots = folder / CHECKPOINT_DIR
    snapshots.mkdir()
    for steps, action in actions.items():
        source = folder.parent / f"{folder.name}-{steps}"
        constant_policy(source, snakebot.rl.GOAL_ENV_ID, action, 20)
        (source / "actor.npz").rename(snapshots / checkpoint_name(steps))
        shutil.rmtree(source)
    return folder


def test_curve_evaluates_every_checkpoint_on_the_same_goals(tmp_path: Path) -> None:
    # Two snapshots of one run: at 100 steps it held still, at 200 it swam ahead; on goals
    # straight ahead the curve goes from no goal to every goal, the same seeds for both points.
    folder = with_checkpoints(
        dft_shift_goal_policy(tmp_path / "run", [0, 1, 0, 0, 0], (0.0, 0.0)),
        {100: [0, 0, 0, 0, 0], 200: [0, 1, 0, 0, 0]},
    )
    done = cli("rl", "curve", str(folder), "--episodes", "2", "--json")
    assert done.returncode == 0, done.stderr
    rows = json.loads(done.stdout)["curve"]
    assert [(r["steps"], r["success_rate"]) for r in rows] == [(100, 0.0), (200, 1.0)]
    with (folder / "eval_curve.csv").open() as f:
        written = list(csv.DictReader(f))
    assert [(r["steps"], float(r["success_rate"])) for r in written] == [("100", 0.0), ("200", 1.0)]
    assert (folder / "eval_curve.png").stat().st_size > 1000
    again = cli("rl", "curve", str(folder), "--episodes", "1")
    assert again.returncode == 1 and "--force" in again.stderr  # the curve is kept
    assert len((folder / "eval_curve.csv").read_text().splitlines()) == 3
    bare = dft_shift_goal_policy(tmp_path / "bare", [0, 1, 0, 0, 0], (0.0, 0.0))
    none = cli("rl", "curve", str(bare))
    assert none.returncode == 1 and "checkpoints" in none.stderr
    assert not (bare / "eval_curve.csv").exists()


def test_compare_draws_every_encoding_side_by_side(tmp_path: Path) -> None:
    out = tmp_path / "compare"
    done = cli(
        "rl",
        "compare",
        "--encodings",
        "sinusoid,dft",
        "--steps",
        "2048",
        "--n-envs",
        "1",
        "--vec",
        "dummy",
        "--out",
        str(out),
        "--json",
        *FAST,
    )
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert set(summary["runs"]) == {"sinusoid", "dft"}
    assert (out / "compare.png").stat().st_size > 10_000
    assert (out / "sinusoid" / "actor.npz").exists() and (out / "dft" / "policy.json").exists()


def test_bad_rl_options_are_named(tmp_path: Path) -> None:
    bad = cli("rl", "train", "--set", "goal_radius=1", "--out", str(tmp_path / "x"))
    assert bad.returncode == 1 and "goal_radius" in bad.stderr and "goal_radius_bl" in bad.stderr
    assert cli("rl", "train", "--encoding", "rotating").returncode == 2
    assert cli("rl", "compare", "--encodings", "dft,nope").returncode == 2  # a flag's value
    assert cli("rl", "eval", str(tmp_path / "none")).returncode == 1


def test_task_seed_trains_at_the_seeds_distances_reward_scale_and_discount(tmp_path: Path) -> None:
    # --task seed: goals 5-7 m from the head, -1 a step and +100 at the goal, 200 s (2000-step)
    # episodes, PPO's gamma 0.999; --set and --ppo still override the preset.
    out = tmp_path / "out"
    train = cli("rl", "train", "--task", "seed", "--out", str(out), "--dry-run", "--json")
    assert train.returncode == 0, train.stderr
    plan = json.loads(train.stdout)
    kwargs = plan["env_kwargs"]
    assert kwargs["goal_distance_m"] == [5.0, 7.0] and kwargs["goal_from"] == "head"
    assert (kwargs["step_cost"], kwargs["goal_bonus"], kwargs["episode_s"]) == (1.0, 100.0, 200.0)
    assert plan["ppo"] == {"gamma": 0.999}
    near = json.loads(cli("rl", "train", "--dry-run", "--json", "--out", str(out)).stdout)
    assert near["env_kwargs"]["goal_distance_m"] is None and near["ppo"] == {}
    both = cli(
        "rl", "compare", "--task", "seed", "--encodings", "sinusoid,dft", "--out", str(out),
        "--set", "goal_bonus=50", "--ppo", "gamma=0.99", "--dry-run", "--json",
    )  # fmt: skip
    assert both.returncode == 0, both.stderr
    plan = json.loads(both.stdout)
    assert {r["goal_bonus"] for r in plan["env_kwargs"].values()} == {50.0}
    assert {r["step_cost"] for r in plan["env_kwargs"].values()} == {1.0}
    assert plan["ppo"] == {"gamma": 0.99}
    velocity = cli("rl", "train", "--env", "snakebot/SnakeVelocity-v0", "--task", "seed",
                   "--dry-run", "--out", str(out))  # fmt: skip
    assert velocity.returncode == 2 and "--task seed" in velocity.stderr
    assert cli("rl", "train", "--task", "far", "--dry-run").returncode == 2
    resumed = cli("rl", "train", "--resume", str(tmp_path / "p"), "--task", "seed", "--dry-run")
    assert resumed.returncode == 2 and "--task" in resumed.stderr  # the saved policy's task
    assert list(tmp_path.iterdir()) == []


def test_the_cli_names_every_goal_task_preset() -> None:
    from snakebot.cli.rl_cmd import TASK_CHOICES
    from snakebot.rl.tasks import GOAL_TASKS

    assert tuple(GOAL_TASKS) == TASK_CHOICES


def test_dry_runs_check_the_settings_and_write_nothing(tmp_path: Path) -> None:
    out = tmp_path / "out"
    train = cli("rl", "train", "--out", str(out / "policy"), "--dry-run", "--json", *FAST)
    assert train.returncode == 0, train.stderr
    plan = json.loads(train.stdout)
    assert plan["dry_run"] is True and plan["env_kwargs"]["action_hz"] == 25
    compare = cli(
        "rl", "compare", "--encodings", "sinusoid,dft", "--out", str(out), "--dry-run", "--json"
    )
    assert compare.returncode == 0, compare.stderr
    assert json.loads(compare.stdout)["encodings"] == ["sinusoid", "dft"]
    bad = cli("rl", "train", "--set", "goal_radius=1", "--dry-run", "--out", str(out))
    assert bad.returncode == 1 and "goal_radius_bl" in bad.stderr  # checked, not just skipped
    body = cli("rl", "train", "--robot", "worm", "--dry-run", "--out", str(out))
    assert body.returncode == 2 and "mass-spring" in body.stderr
    assert list(tmp_path.iterdir()) == []
