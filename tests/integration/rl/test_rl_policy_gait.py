"""A trained policy is a gait: the runner plays it through the safety layer exactly as the env
stepped it; a goal policy is refused where no pose source exists."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import gymnasium
import numpy as np
import pytest

import snakebot.rl
from snakebot.backends.chain import ServoChainBackend
from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.errors import ConfigError, GaitError
from snakebot.rl.policy_file import load_policy
from snakebot.rl.policy_gait import PolicyGait, policy_gait_for_backend
from snakebot.types import BodyState
from tests.integration.rl.policies import constant_policy, random_policy

GOAL, VELOCITY = snakebot.rl.GOAL_ENV_ID, snakebot.rl.VELOCITY_ENV_ID


def test_the_runner_plays_a_velocity_policy_exactly_as_the_env_stepped_it(
    tmp_path: Path,
) -> None:
    """Redundant by construction since the env steps a CycleLoop: both sides now run one gait
    class (PolicyGait is the env's ActionGait deciding its own actions) through one CycleLoop
    (gait_step: the same schedule, ramp, slew period and safety layer) on the twin the env
    resets with its own Resettable.reset; nothing is left that could make them differ but the
    observation, the decision times and the phases' start, which this still pins. Kept (and
    made exact: equal bits, not 1e-6) as the end-to-end guard it was before."""
    # Random weights: every action depends on what the policy observes, so any difference in
    # observation, phase or timing between env and runner would show in the joints.
    folder = random_policy(
        tmp_path / "p", VELOCITY, 5, 3 * 8 + 2 + 2, seed=4, encoding="dft_shift", control_hz=50
    )
    policy = load_policy(folder)
    env = gymnasium.make(VELOCITY, **policy.env_kwargs)
    env.reset(seed=0, options={"command": (0.1, 0.2)})
    loop = env.unwrapped.loop
    loop.reset(0.0)  # the runner starts its phases at 0; the env draws them
    obs = env.unwrapped._obs()
    for _ in range(20):  # 2 s
        obs, *_ = env.step(policy.actor(obs).astype(np.float32))
    env_joints = loop.backend.read_state().position_rad
    env.close()

    robot = load_robot("snake8")
    with TwinBackend(robot) as backend:
        name, gait = policy_gait_for_backend(str(folder), robot, backend, (0.1, 0.2), 50.0)
        assert name == "policy:velocity:dft_shift"
        run_gait(
            backend,
            gait,
            SafetyLayer.for_robot(robot),
            RunPlan(2.0, 50.0, ramp_out=False),
            RunMetrics(8, robot.body_length_m, robot.total_mass_kg),
        )
        run_joints = backend.read_state().position_rad
        assert gait.decisions == 20
    np.testing.assert_array_equal(run_joints, env_joints)


def test_a_goal_policy_on_the_bus_is_refused_naming_the_missing_pose_source(
    tmp_path: Path,
) -> None:
    folder = constant_policy(
        tmp_path / "goal", GOAL, [0, 0, 0, 0], 2 * 8 + 2 + 2, encoding="sinusoid"
    )
    robot = load_robot("snake8")
    bus = ServoChainBackend(robot, port="/dev/null")  # never connected
    with pytest.raises(ConfigError, match="no pose source"):
        policy_gait_for_backend(str(folder), robot, bus, (1.0, 0.0), 100.0)


class OverheadCamera:
    """A pose source as a user plugs one in: here it reads a twin, as a camera would see it."""

    def __init__(self, twin: TwinBackend) -> None:
        self.twin = twin
        self.calls = 0

    def body_state(self) -> BodyState | None:
        self.calls += 1
        return self.twin.body_state()


def test_a_goal_policy_runs_with_a_plugged_in_pose_source(tmp_path: Path) -> None:
    folder = constant_policy(
        tmp_path / "goal", GOAL, [0, 0, 0, 0], 2 * 8 + 2 + 2, encoding="sinusoid"
    )
    robot = load_robot("snake8")
    with TwinBackend(robot) as twin:
        camera = OverheadCamera(twin)
        gait = PolicyGait(load_policy(folder), robot, twin.read_state, (1.0, 0.0), pose=camera)
        metrics = RunMetrics(8, robot.body_length_m, robot.total_mass_kg)
        run_gait(twin, gait, SafetyLayer.for_robot(robot), RunPlan(3.0, 100.0), metrics)
    assert camera.calls == gait.decisions == 40  # 3 s of gait and 1 s of ramp-out at 10 Hz
    assert gait.goal_xy_m is not None
    assert metrics.summary(None)["distance_m"] > 0.3  # type: ignore[operator]


def test_policy_and_robot_must_fit(tmp_path: Path) -> None:
    folder = constant_policy(
        tmp_path / "v", VELOCITY, [0, 0, 0, 0], 3 * 8 + 2 + 2, encoding="sinusoid"
    )
    snake12 = load_robot("snake12")
    with pytest.raises(ConfigError, match="trained on 'snake8'"):
        PolicyGait(load_policy(folder), snake12, lambda: None, (0.1, 0.0))  # type: ignore[arg-type,return-value]
    gait = PolicyGait(load_policy(folder), load_robot("snake8"), lambda: None, (0.1, 0.0))  # type: ignore[arg-type,return-value]
    with pytest.raises(GaitError, match="closed-loop"):
        gait.targets(0.0)


def snakebot(*args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "snakebot", *args], capture_output=True, text=True, timeout=timeout
    )


def test_run_policy_on_the_twin_moves_and_reports(tmp_path: Path) -> None:
    folder = constant_policy(
        tmp_path / "v", VELOCITY, [0, 0, 0, 0], 3 * 8 + 2 + 2, encoding="sinusoid"
    )
    log = tmp_path / "run.csv"
    done = snakebot(
        "run",
        "--policy",
        str(folder),
        "--command",
        "0.2,0",
        "--duration",
        "4",
        "--log",
        str(log),
        "--json",
    )
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["gait"] == "policy:velocity:sinusoid"
    assert summary["speed_mps"] > 0.1
    assert log.read_text().count("\n") > 400  # telemetry every cycle, ramp-out included


def test_run_policy_usage_and_config_errors(tmp_path: Path) -> None:
    goal = constant_policy(tmp_path / "g", GOAL, [0, 0, 0, 0], 2 * 8 + 2 + 2, encoding="sinusoid")
    refused = snakebot(
        "run",
        "--backend",
        "dynamixel",
        "--robot",
        "snake8",
        "--port",
        "/dev/ttyUSB9",
        "--policy",
        str(goal),
        "--command",
        "1,0",
    )
    assert refused.returncode == 1
    assert "no pose source" in refused.stderr
    assert snakebot("run", "--command", "1,0").returncode == 2
    assert (
        snakebot("run", "--policy", str(goal), "--gait", "serpenoid", "--command", "1,0").returncode
        == 2
    )
    missing = snakebot("run", "--policy", str(goal))  # a missing option: usage
    assert missing.returncode == 2 and "--command" in missing.stderr
    body = snakebot("run", "--robot", "worm", "--policy", str(goal), "--command", "1,0")
    assert body.returncode == 2 and "mass-spring body" in body.stderr
    nothing = snakebot("run", "--policy", str(tmp_path / "nope"), "--command", "1,0")
    assert nothing.returncode == 1 and "no such policy folder" in nothing.stderr
