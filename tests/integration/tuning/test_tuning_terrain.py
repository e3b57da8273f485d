"""Tuning on a terrain: both engines run candidates there exactly as `snakebot run` does, scale
friction included (it runs inside mj_step, so mujoco.batch threads get it too)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.terrain import parse_terrain
from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from snakebot.tuning.commands import GaitCommands
from snakebot.tuning.engine import TwinBatch
from snakebot.tuning.feasibility import Envelope
from snakebot.tuning.pool import PoolJob, ProcessPool
from snakebot.tuning.trace import summarise

TERRAIN = parse_terrain("rough:roughness_m=0.003,seed=2")
PARAMS = [{"omega": 4.0, "phase_lag": 0.6}, {"omega": 2.0, "amplitude": 0.6}]
KEYS = ("distance_m", "tracking_rms_rad", "positive_work_j", "turn_deg")


def test_batch_pool_and_runner_agree_bit_for_bit_with_scale_friction() -> None:
    robot = load_robot("snake8")
    gaits = [make_gait("serpenoid", 8, p) for p in PARAMS]
    batch = TwinBatch(robot, terrain=TERRAIN)
    traces = batch.run(GaitCommands(gaits, robot), 1.5, 100.0)
    envelope = Envelope.for_robot(robot, float(batch.start_com_m[2]))
    jobs = [PoolJob(robot, "serpenoid", p, 1.5, 100.0, envelope, terrain=TERRAIN) for p in PARAMS]
    with ProcessPool(2) as pool:
        pooled = pool.run(jobs)
    for params, gait, trace, other in zip(PARAMS, gaits, traces, pooled, strict=True):
        metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
        with TwinBackend(robot, terrain=TERRAIN) as twin:
            expected = run_gait(
                twin, make_gait("serpenoid", 8, params), SafetyLayer.for_robot(robot),
                RunPlan(1.5), metrics,
            ).summary  # fmt: skip
        assert float(expected["distance_m"]) > 0.03  # type: ignore[arg-type]
        for summary in (summarise(trace, robot, gait.period_s), summarise(other, robot, None)):
            assert {k: summary[k] for k in KEYS} == {k: expected[k] for k in KEYS}
        assert np.array_equal(trace.position_rad, other.position_rad)


def test_tune_gait_takes_a_terrain_and_reports_it(capsys: pytest.CaptureFixture[str]) -> None:
    argv = [
        "tune", "gait", "--robot", "snake8", "--method", "grid", "--budget", "4", "--duration",
        "1", "--quiet", "--json", "--terrain", "step:height_m=0.02", "--friction-model", "scale",
    ]  # fmt: skip
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["terrain"].startswith("step:height_m=0.02,")
    assert summary["evaluations"] == 4
