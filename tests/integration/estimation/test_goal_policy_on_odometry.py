"""A goal policy whose pose is the odometry (what ``run --policy --odometry`` does), on the twin."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.cli.goto_options import odometry_for
from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer

pytest.importorskip("gymnasium")

from snakebot.rl.policy_file import load_policy
from snakebot.rl.policy_gait import PolicyGait
from snakebot.rl.settings import GOAL_ENV_ID
from tests.integration.rl.policies import constant_policy


def _goal_policy(folder: Path) -> Path:
    return constant_policy(folder, GOAL_ENV_ID, [0, 0, 0, 0], 2 * 8 + 2 + 2, encoding="sinusoid")


def test_a_goal_policy_plays_on_the_odometry_and_sees_the_true_goal(tmp_path: Path) -> None:
    robot = load_robot("snake8")
    odometry = odometry_for(robot)
    with TwinBackend(robot) as twin:
        odometry.start(twin.read_state())
        gait = PolicyGait(
            load_policy(_goal_policy(tmp_path / "goal")),
            robot,
            twin.read_state,
            (1.0, 0.0),
            pose=odometry,
        )
        start = twin.body_state().com_m.copy()
        metrics = RunMetrics(8, robot.body_length_m, robot.total_mass_kg)
        plan = RunPlan(3.0, 100.0, ramp_out=False)
        run_gait(twin, gait, SafetyLayer.for_robot(robot), plan, metrics, observers=[odometry])
        end = twin.body_state().com_m
    assert gait.decisions == 30 and gait.goal_xy_m is not None
    # The goal is 1 m ahead of the true start: the estimate's world is the twin's at the start.
    np.testing.assert_allclose(gait.goal_xy_m, start[:2] + np.array([1.0, 0.0]), atol=0.01)
    body = odometry.body_state()
    assert body is not None
    assert np.hypot(*(body.com_m[:2] - end[:2])) < 0.1 * max(np.hypot(*(end - start)[:2]), 0.3)


def test_run_policy_with_odometry_on_the_command_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = _goal_policy(tmp_path / "goal")
    argv = ["run", "--policy", str(folder), "--odometry", "--command", "1,0", "--duration", "2"]
    assert main([*argv, "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["gait"] == "policy:goal:sinusoid" and summary["distance_m"] > 0.1
