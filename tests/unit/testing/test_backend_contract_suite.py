"""snakebot.testing.BackendContract catches a faulty backend: run by pytest on a third party's
test module (in a subprocess, as their CI would), it fails exactly the checks the fault breaks."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

MODULE = """
import numpy as np

from snakebot.backends.base import Backend
from snakebot.types import JointState
from snakebot.testing import BackendContract


class Perfect(Backend):
    def __init__(self, robot):
        super().__init__()
        self.joint_count = robot.joint_count
        self.stop_policy = robot.safety.stop_policy
        self.now_s = 0.0
        self.goal = np.zeros(self.joint_count)

    def _connect(self):
        self.torque_enabled = True

    def _close(self):
        self.set_torque(self.stop_policy == "hold")

    def _read_state(self):
        zero = np.zeros(self.joint_count)
        return JointState(self.now_s, self.goal.copy(), zero, zero)

    def _send_command(self, position_rad):
        self.goal = position_rad.copy()

    def _set_gains(self, gains):
        pass

    def _set_torque(self, enabled):
        self.torque_enabled = enabled

    def _advance(self, dt_s):
        self.now_s += dt_s * TIME_SCALE


class TestPerfect(BackendContract):
    def make(self, robot):
        return Perfect(robot)
"""


def run_suite(tmp_path: Path, time_scale: float) -> dict[str, str]:
    module = tmp_path / "test_third_party_backend.py"
    module.write_text(f"TIME_SCALE = {time_scale}\n{MODULE}", encoding="utf-8")
    result = subprocess.run(
        [sys.executable, "-m", "pytest", str(module), "-q", "-rA", "-p", "no:cacheprovider",
         "--rootdir", str(tmp_path)],
        capture_output=True, text=True, cwd=tmp_path, timeout=300,
    )  # fmt: skip
    lines = re.findall(r"^(PASSED|FAILED) \S+::TestPerfect::(\w+)", result.stdout, re.M)
    outcomes = {name: outcome for outcome, name in lines}
    assert outcomes, result.stdout + result.stderr
    return outcomes


def test_a_correct_backend_passes_every_check(tmp_path: Path) -> None:
    outcomes = run_suite(tmp_path, 1.0)
    assert set(outcomes.values()) == {"PASSED"}
    assert len(outcomes) == 9


@pytest.mark.parametrize("time_scale", [0.0, 2.0])
def test_a_backend_whose_clock_is_wrong_fails_the_time_check_only(
    tmp_path: Path, time_scale: float
) -> None:
    outcomes = run_suite(tmp_path, time_scale)
    failed = {name for name, outcome in outcomes.items() if outcome == "FAILED"}
    assert failed == {"test_advance_moves_time_by_dt"}
