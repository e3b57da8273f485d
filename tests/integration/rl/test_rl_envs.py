"""The Gymnasium environments: check_env with warnings as errors for every env x encoding,
determinism under a seed, vector envs, the reward's signs, the safety layer in the loop."""

from __future__ import annotations

import math
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import snakebot.rl
from snakebot.config import load_robot
from snakebot.errors import ConfigError

GOAL, VELOCITY = snakebot.rl.GOAL_ENV_ID, snakebot.rl.VELOCITY_ENV_ID


@pytest.mark.parametrize("encoding", snakebot.rl.ENCODINGS)
@pytest.mark.parametrize("env_id", snakebot.rl.ENV_IDS)
def test_every_env_and_encoding_passes_check_env_with_warnings_as_errors(
    env_id: str, encoding: str
) -> None:
    env = gymnasium.make(env_id, encoding=encoding)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            check_env(env.unwrapped)  # includes the rgb_array render check
    finally:
        env.close()


def rollout(env_id: str, seed: int, steps: int, **kwargs: object) -> list[tuple]:
    env = gymnasium.make(env_id, **kwargs)
    env.action_space.seed(seed)
    obs, info = env.reset(seed=seed)
    out = [(obs, 0.0, info)]
    for _ in range(steps):
        obs, reward, _, _, info = env.step(env.action_space.sample())
        out.append((obs, reward, info))
    env.close()
    return out


@pytest.mark.parametrize("env_id", snakebot.rl.ENV_IDS)
def test_same_seed_same_episode_other_seed_other_episode(env_id: str) -> None:
    a = rollout(env_id, 7, 6, encoding="sinusoid")
    b = rollout(env_id, 7, 6, encoding="sinusoid")
    c = rollout(env_id, 8, 6, encoding="sinusoid")
    for (obs_a, r_a, _), (obs_b, r_b, _) in zip(a, b, strict=True):
        np.testing.assert_array_equal(obs_a, obs_b)
        assert r_a == r_b
    assert not np.array_equal(a[-1][0], c[-1][0])


def test_goal_reward_pays_for_moving_toward_the_goal_not_away() -> None:
    forward = np.array([0.0, 0.0, 0.0, 0.0], dtype=np.float32)  # a serpenoid that moves ahead
    velocity = {}
    for name, goal in (("ahead", (3.0, 0.0)), ("behind", (-3.0, 0.0))):
        env = gymnasium.make(GOAL, encoding="sinusoid")
        env.reset(seed=0, options={"goal_xy_m": goal})
        terms = [env.step(forward)[4]["reward_terms"] for _ in range(40)]
        velocity[name] = sum(t["velocity"] for t in terms)
        assert all(set(t) == {"step", "velocity", "distance", "goal"} for t in terms)
        env.close()
    assert velocity["ahead"] > 1.0
    assert velocity["behind"] < -1.0


def test_reaching_the_goal_terminates_with_the_bonus() -> None:
    env = gymnasium.make(GOAL, encoding="sinusoid", goal_radius_bl=0.5)
    env.reset(seed=0, options={"goal_xy_m": (0.8, 0.0)})  # 1.4 body lengths ahead
    steps = 0
    for steps in range(1, 201):  # noqa: B007 (the count is the result)
        _, _, terminated, truncated, info = env.step(np.zeros(4, dtype=np.float32))
        if terminated:
            break
    assert terminated and not truncated and info["is_success"]
    assert info["reward_terms"]["goal"] == 10.0 and info["distance_bl"] <= 0.5
    assert steps < 100
    env.close()


def test_goals_are_drawn_all_around_at_the_configured_distance() -> None:
    env = gymnasium.make(GOAL, encoding="dft", goal_distance_bl=(2.0, 3.0))
    length = load_robot("snake8").body_length_m
    bearings = []
    for seed in range(40):
        _, info = env.reset(seed=seed)
        assert 2.0 - 1e-9 <= info["distance_bl"] <= 3.0 + 1e-9
        com = env.unwrapped.loop.body().com_m[:2]
        dx, dy = (info["goal_xy_m"] - com) / length
        bearings.append(math.atan2(dy, dx))
    env.close()
    assert max(bearings) > 2.0 and min(bearings) < -2.0  # ahead, behind, left and right


def test_the_seeds_task_puts_goals_5_to_7_m_from_the_head_and_pays_its_reward_scale() -> None:
    # The seed: "a random objective is created within 5 to 7 meters from the snake's head
    # position"; -1 a step, +100 at the goal. The task preset `rl train --task seed` sets these.
    from snakebot.rl.tasks import goal_task

    seed_task = goal_task("seed").env
    env = gymnasium.make(GOAL, encoding="dft", **seed_task)
    loop = env.unwrapped.loop
    from_head, from_com = [], []
    for seed in range(20):
        _, info = env.reset(seed=seed)
        from_head.append(float(np.linalg.norm(info["goal_xy_m"] - loop.head_xy_m())))
        from_com.append(float(np.linalg.norm(info["goal_xy_m"] - loop.body().com_m[:2])))
    assert min(from_head) >= 5.0 - 1e-9 and max(from_head) <= 7.0 + 1e-9
    assert max(from_head) - min(from_head) > 1.0  # drawn across the range
    assert max(abs(h - c) for h, c in zip(from_head, from_com, strict=True)) > 0.1  # not the COM
    _, reward, _, _, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    assert info["reward_terms"]["step"] == -1.0 and reward < -1.0  # held still: no velocity pay
    assert env.unwrapped.settings.max_steps == 2000  # the seed's max path length
    env.close()


def test_goal_settings_name_a_bad_origin_or_distance() -> None:
    with pytest.raises(ConfigError, match=r"goal_from.*com, head.*'tail'"):
        gymnasium.make(GOAL, goal_from="tail")
    with pytest.raises(ConfigError, match=r"goal_distance_m.*low <= high"):
        gymnasium.make(GOAL, goal_distance_m=(7.0, 5.0))
    with pytest.raises(ConfigError, match=r"goal_distance_m.*low <= high"):
        gymnasium.make(GOAL, goal_distance_m=(-1.0, 5.0))


def test_episodes_truncate_at_episode_s() -> None:
    env = gymnasium.make(VELOCITY, encoding="dft", episode_s=1.0, action_hz=10, control_hz=50)
    env.reset(seed=0)
    flags = [env.step(np.zeros(5, dtype=np.float32))[3] for _ in range(10)]
    assert flags == [False] * 9 + [True]
    env.close()


def test_envs_take_the_twins_terrains() -> None:
    # The same --terrain text as `snakebot run`: a 10 degree slope tilts the ground under the
    # snake (its start pose follows it), and a bad key is a ConfigError naming it.
    env = gymnasium.make(GOAL, encoding="sinusoid", terrain="slope:angle_deg=10")
    env.reset(seed=0)
    twin = env.unwrapped.loop.backend
    assert type(twin.terrain).__name__ == "Slope"
    for _ in range(5):
        env.step(np.zeros(4, dtype=np.float32))
    env.close()
    with pytest.raises(ConfigError, match="angle_deg"):
        gymnasium.make(GOAL, encoding="sinusoid", terrain="slope:angle_deg=90").reset(seed=0)


def test_velocity_env_measures_the_speed_the_snake_moves_at() -> None:
    env = gymnasium.make(VELOCITY, encoding="sinusoid")
    env.reset(seed=0, options={"command": (0.1, 0.0)})
    com0 = env.unwrapped.loop.body().com_m[:2].copy()
    speeds = [env.step(np.zeros(4, dtype=np.float32))[4]["speed_mps"] for _ in range(50)]
    com1 = env.unwrapped.loop.body().com_m[:2]
    travelled = float(np.linalg.norm(com1 - com0)) / 5.0
    assert travelled > 0.1
    assert np.mean(speeds) == pytest.approx(travelled, rel=0.25)
    env.close()


def test_velocity_observation_holds_only_what_servos_report_and_the_command() -> None:
    env = gymnasium.make(VELOCITY, encoding="sinusoid")
    obs, _ = env.reset(seed=0, options={"command": (0.35, -0.3)})
    n = 8
    assert obs.shape == (3 * n + 2 + 2,)
    np.testing.assert_allclose(obs[-2:], [1.0, -1.0])  # the command, scaled by its ranges
    # Moving the snake's body elsewhere (a pose no servo can see) changes nothing observed.
    env.unwrapped.loop.backend.data.qpos[:2] += 5.0
    np.testing.assert_array_equal(env.unwrapped._obs(), obs)
    env.close()


def test_the_safety_layer_limits_what_reaches_the_twin() -> None:
    robot = load_robot("snake8")
    env = gymnasium.make(GOAL, encoding="simple", control_hz=50)
    env.reset(seed=0)
    data = env.unwrapped.loop.backend.data
    last = data.ctrl.copy()
    for k in range(30):
        action = np.full(8, 1.0 if k % 2 else -1.0, dtype=np.float32)  # full bang-bang
        env.step(action)
        assert np.all(data.ctrl <= robot.upper_rad) and np.all(data.ctrl >= robot.lower_rad)
        # five control cycles per step, each at most the servo speed limit
        assert np.abs(data.ctrl - last).max() <= 5 * robot.max_speed_rad_s / 50 + 1e-9
        last = data.ctrl.copy()
    env.close()


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_make_vec_runs_both_envs(mode: str) -> None:
    for env_id in snakebot.rl.ENV_IDS:
        envs = gymnasium.make_vec(env_id, num_envs=2, vectorization_mode=mode, encoding="dft_shift")
        obs, _ = envs.reset(seed=3)
        assert obs.shape[0] == 2 and not np.array_equal(obs[0], obs[1])
        for _ in range(3):
            obs, rewards, _, _, _ = envs.step(envs.action_space.sample())
        assert rewards.shape == (2,) and np.all(np.isfinite(rewards))
        envs.close()


def test_render_is_an_rgb_frame() -> None:
    env = gymnasium.make(GOAL, encoding="sinusoid", render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (480, 640, 3) and frame.dtype == np.uint8 and frame.std() > 5
    env.close()


def test_bad_settings_name_the_setting() -> None:
    with pytest.raises(ConfigError, match=r"goal_distanse_bl.*goal_distance_bl"):
        gymnasium.make(GOAL, goal_distanse_bl=(1, 2))
    with pytest.raises(ConfigError, match=r"control_hz.*whole multiple"):
        gymnasium.make(GOAL, action_hz=10, control_hz=25)
    with pytest.raises(ConfigError, match=r"encoding.*dft_shift"):
        gymnasium.make(VELOCITY, encoding="rotating_dft")


def test_an_episode_past_a_hard_physics_limit_ends_truncated_and_training_goes_on() -> None:
    # Measured: a SnakeVelocity training run died at 8,192 steps when one exploring episode
    # pushed a module 11.2 mm into the ground (limit 11.0): PhysicsHealthError in a subprocess
    # worker, EOFError in PPO, exit 3. An episode the twin cannot simulate credibly ends there;
    # the next starts with a fresh account.
    from snakebot.backends.twin.health import HealthLimits

    env = gymnasium.make(VELOCITY, encoding="sinusoid").unwrapped
    try:
        env.reset(seed=0)
        backend = env.loop.backend
        # any joint speed above 1 % of the servo's no-load speed is now "not credible"
        backend.reset_physics_health(HealthLimits(speed_error=0.01))
        action = np.array([1.0, 1.0, 0.0, 0.0], dtype=np.float32)
        ends = []
        for _ in range(20):
            _, reward, terminated, truncated, info = env.step(action)
            if truncated:
                ends.append(info)
                break
        assert ends, "the tight limit never tripped"
        assert not terminated and math.isfinite(reward)
        assert "physics health: joint speed" in ends[0]["physics_health_error"]
        env.reset(seed=1)
        assert backend.physics_monitor is not None and backend.physics_monitor.cycles == 0
        _, _, _, truncated, info = env.step(np.zeros(4, dtype=np.float32))
        assert "physics_health_error" not in info  # the first cycles hold still: credible
    finally:
        env.close()


def test_an_episode_after_reset_repeats_the_first_to_the_bit() -> None:
    # The twin's own reset (Resettable) and a fresh CycleLoop leave nothing of the last
    # episode behind: pose, time, gait phases, the safety layer's last command, the metrics.
    env = gymnasium.make(VELOCITY, encoding="dft_shift").unwrapped
    try:
        episodes = []
        for _ in range(2):
            env.action_space.seed(11)
            obs, _ = env.reset(seed=4, options={"command": (0.2, 0.1)})
            rows = [obs]
            for _ in range(8):
                obs, reward, _, _, info = env.step(env.action_space.sample())
                rows += [obs, np.array([reward, info["positive_work_j"]])]
            assert env.loop.state.time_s == pytest.approx(8 * 0.1)
            episodes.append(rows)
        for first, again in zip(*episodes, strict=True):
            np.testing.assert_array_equal(first, again)
    finally:
        env.close()
