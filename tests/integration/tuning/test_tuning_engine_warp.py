"""The MuJoCo Warp engine, on Warp's CPU device: it scores candidates as the CPU engine does
(within docs/tuning.md's measured tolerance), ranks them the same way, and runs `tune gait`.

Tiny batches and short runs: on the CPU device every physics step is ~100 kernel launches from
Python, whatever the batch size. Run with ``-m warp``; skipped without the gpu extra.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator

import numpy as np
import pytest
from scipy.stats import spearmanr

from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.errors import ConfigError
from snakebot.tuning.objectives import objective_for
from snakebot.tuning.problem import EvalPlan, Evaluation, GaitProblem
from snakebot.tuning.space import build_space, tuning_base

pytestmark = pytest.mark.warp

DURATION_S = 1.0
# omega, phase_lag: speeds 3 mm/s apart or more; the last two ask for joint speeds beyond the
# safety layer's limit (by 19 % and 34 %), so they are infeasible and rank by how far.
POINTS = [(4.5, 0.2), (6.0, 1.2), (3.14, 0.7), (12.0, 0.9), (16.0, 0.3), (18.0, 1.5)]
# The documented tolerances (docs/tuning.md, "The Warp engine"), with margin over the measured.
DISTANCE_TOLERANCE_M = 0.004
WORK_TOLERANCE = 0.05  # relative
TURN_TOLERANCE_DEG = 3.0
TRACKING_TOLERANCE_RAD = 0.005


@pytest.fixture(scope="module")
def both_engines() -> Iterator[tuple[list[Evaluation], list[Evaluation]]]:
    pytest.importorskip("mujoco_warp")
    from snakebot.tuning.engine_warp import WarpGaitProblem

    robot = load_robot("snake12")
    space = build_space("serpenoid", tuning_base("serpenoid", 12, {}), None, {}, 1.0)
    objective = objective_for("speed", 0.0, robot.body_length_m)
    plan = EvalPlan(duration_s=DURATION_S)
    points = [np.array(p) for p in POINTS]
    cpu = GaitProblem(robot, space, objective, plan).evaluate(points)
    warp = WarpGaitProblem(robot, space, objective, EvalPlan(duration_s=DURATION_S, engine="warp"))
    yield cpu, warp.evaluate(points)


def test_each_metric_agrees_with_the_cpu_engine(
    both_engines: tuple[list[Evaluation], list[Evaluation]],
) -> None:
    for cpu, warp in zip(*both_engines, strict=True):
        a, b = cpu.summary, warp.summary
        assert a.keys() == b.keys()
        assert a["control_cycles"] == b["control_cycles"] == 100
        assert a["duration_s"] == b["duration_s"]
        assert a["max_abs_command_rad"] == pytest.approx(b["max_abs_command_rad"], abs=1e-6)
        assert abs(float(a["distance_m"]) - float(b["distance_m"])) < DISTANCE_TOLERANCE_M  # type: ignore[arg-type]
        work_a, work_b = float(a["positive_work_j"]), float(b["positive_work_j"])  # type: ignore[arg-type]
        assert abs(work_a - work_b) <= WORK_TOLERANCE * work_a
        assert abs(float(a["turn_deg"]) - float(b["turn_deg"])) < TURN_TOLERANCE_DEG  # type: ignore[arg-type]
        tracking = float(a["tracking_rms_rad"]) - float(b["tracking_rms_rad"])  # type: ignore[arg-type]
        assert abs(tracking) < TRACKING_TOLERANCE_RAD
        assert cpu.feasible == warp.feasible
        assert warp.violations.stopped == cpu.violations.stopped == ""
        assert warp.violations.speed_excess == pytest.approx(cpu.violations.speed_excess, abs=0.01)


def test_the_candidates_rank_the_same_on_both_engines(
    both_engines: tuple[list[Evaluation], list[Evaluation]],
) -> None:
    cpu, warp = ([e.loss for e in evaluations] for evaluations in both_engines)
    assert [e.feasible for e in both_engines[0]] == [True] * 4 + [False] * 2
    assert len(set(cpu)) == len(cpu)  # no ties: the ranking is defined
    assert spearmanr(cpu, warp).statistic == pytest.approx(1.0)
    assert int(np.argmin(cpu)) == int(np.argmin(warp))


def test_tune_gait_runs_on_the_warp_engine(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("mujoco_warp")
    argv = [
        "tune", "gait", "--robot", "snake12", "--gait", "sidewinding", "--params",
        "amplitude_even", "--method", "grid", "--budget", "4", "--duration", "0.2",
        "--engine", "warp", "--device", "cpu", "--quiet", "--json", "--dry-run",
    ]  # fmt: skip
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert (summary["engine"], summary["device"]) == ("warp", "cpu")
    assert summary["evaluations"] == 4
    assert math.isfinite(summary["best"]["loss"]) and summary["best"]["feasible"]


def test_a_device_warp_does_not_have_is_a_config_error() -> None:
    pytest.importorskip("mujoco_warp")
    from snakebot.tuning.engine import TwinBatch
    from snakebot.tuning.engine_warp import WarpBatch
    from snakebot.tuning.feasibility import Envelope

    robot = load_robot("snake8")
    twin = TwinBatch(robot)
    envelope = Envelope.for_robot(robot, float(twin.start_com_m[2]))
    with pytest.raises(ConfigError, match="device"):
        WarpBatch(twin, envelope, device="cuda:7")


def test_a_feedback_gait_reads_the_device_poses_every_cycle() -> None:
    """Keyframes that wait for the measured pose (closed loop, one cycle per upload): the Warp
    engine feeds back its own poses and ends where the CPU engine does."""
    pytest.importorskip("mujoco_warp")
    from snakebot.gaits import make_gait
    from snakebot.tuning.commands import GaitCommands
    from snakebot.tuning.engine import TwinBatch
    from snakebot.tuning.engine_warp import WarpBatch
    from snakebot.tuning.feasibility import Envelope
    from snakebot.tuning.trace import summarise
    from snakebot.tuning.warp_scores import outcomes

    robot = load_robot("snake8")
    waiting = {"advance": "error", "durations": (0.3,), "error_threshold_rad": 0.05}
    twin = TwinBatch(robot)
    envelope = Envelope.for_robot(robot, float(twin.start_com_m[2]))
    cpu_commands = GaitCommands([make_gait("keyframes", 8, waiting)], robot)
    assert not cpu_commands.open_loop
    trace = twin.run(cpu_commands, 0.6, 100.0, envelope=envelope)[0]
    gait = make_gait("keyframes", 8, waiting)
    run = WarpBatch(twin, envelope).run(GaitCommands([gait], robot), 0.6, 100.0)
    start = twin.start_com_m
    ((summary, violations),) = outcomes(run, robot, envelope, 0.6, [gait.period_s], start)
    expected = summarise(trace, robot, gait.period_s)
    assert summary["control_cycles"] == expected["control_cycles"] == 60
    for key, tolerance in (("tracking_rms_rad", 0.005), ("max_abs_command_rad", 0.01)):
        assert abs(float(summary[key]) - float(expected[key])) < tolerance, key  # type: ignore[arg-type]
    assert abs(float(summary["distance_m"]) - float(expected["distance_m"])) < DISTANCE_TOLERANCE_M  # type: ignore[arg-type]
    assert violations.feasible
