from __future__ import annotations

import sys

import numpy as np
import pytest

from snakebot.config import load_robot
from snakebot.control.cycle import CycleSchedule
from snakebot.control.safety import SafetyLayer
from snakebot.errors import MissingDependencyError
from snakebot.gaits import make_gait
from snakebot.tuning.commands import GaitCommands


def test_batched_commands_equal_one_safety_layer_per_gait() -> None:
    robot = load_robot("snake8")
    params = [{"omega": 12.0, "amplitude": 1.4}, {"omega": 2.0}, {"phase_lag": 0.2}]
    gaits = [make_gait("serpenoid", 8, p) for p in params]
    batch = GaitCommands(gaits, robot)
    start = np.zeros((3, 8))
    schedule = CycleSchedule(100.0, 1.5, robot.safety.ramp_s)
    batch.reset(start, schedule)
    singles = [SafetyLayer.for_robot(robot) for _ in gaits]
    for layer in singles:
        layer.reset(np.zeros(8))
    for k in range(150):
        t = k * 0.01
        _, sent = batch(k, t, start)
        for b, (gait, layer) in enumerate(zip(gaits, singles, strict=True)):
            expected = layer.filter(gait.command(t), 0.01, schedule.ramp_in(t))
            assert np.array_equal(sent[b], expected)


def test_cmaes_without_the_cma_package_says_how_to_install_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from snakebot.tuning.cmaes import require_cma

    monkeypatch.setitem(sys.modules, "cma", None)
    with pytest.raises(MissingDependencyError, match=r"pip install 'snakebot\[tune\]'"):
        require_cma()


def test_a_batch_is_open_loop_unless_a_gait_uses_the_measured_pose() -> None:
    robot = load_robot("snake8")
    timed = [make_gait("serpenoid", 8), make_gait("keyframes", 8)]
    assert GaitCommands(timed, robot).open_loop
    waiting = make_gait("keyframes", 8, {"advance": "error", "durations": (0.1,)})
    batch = GaitCommands([make_gait("serpenoid", 8), waiting], robot)
    assert not batch.open_loop
    far = np.full((2, 8), 0.0)
    batch.reset(far, CycleSchedule(100.0, 1.0))
    targets = [batch(k, k * 0.01, far)[0][1] for k in range(40)]
    assert np.array_equal(targets[-1], targets[-2])  # holds keyframe 1 until the pose is reached
