"""The batch engine and the process pool run candidates exactly as `snakebot run` does."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.errors import SimulationDivergedError
from snakebot.gaits import make_gait
from snakebot.tuning.commands import ArrayCommands, GaitCommands
from snakebot.tuning.engine import TwinBatch
from snakebot.tuning.feasibility import Envelope
from snakebot.tuning.pool import PoolJob, ProcessPool
from snakebot.tuning.trace import summarise
from tests.integration.twin.robots import with_delay

PARAMS = [{"omega": 6.0, "phase_lag": 0.5}, {"omega": 2.0, "amplitude": 0.6}]
STATE = mujoco.mjtState.mjSTATE_INTEGRATION
KEYS = ("distance_m", "tracking_rms_rad", "positive_work_j", "turn_deg", "cost_of_transport")


def runner_summary(robot_name: str, gait: str, params: dict[str, float]) -> dict[str, object]:
    robot = load_robot(robot_name)
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    with TwinBackend(robot) as twin:
        result = run_gait(
            twin,
            make_gait(gait, robot.joint_count, params),
            SafetyLayer.for_robot(robot),
            RunPlan(1.5),
            metrics,
        )
    return result.summary


def test_batched_and_pooled_runs_match_the_runner_bit_for_bit() -> None:
    robot = load_robot("snake8")
    gaits = [make_gait("serpenoid", 8, p) for p in PARAMS]
    batch = TwinBatch(robot)
    traces = batch.run(GaitCommands(gaits, robot), 1.5, 100.0)
    envelope = Envelope.for_robot(robot, float(batch.start_com_m[2]))
    with ProcessPool(2) as pool:
        pooled = pool.run([PoolJob(robot, "serpenoid", p, 1.5, 100.0, envelope) for p in PARAMS])
    for params, gait, trace, other in zip(PARAMS, gaits, traces, pooled, strict=True):
        expected = runner_summary("snake8", "serpenoid", params)
        for summary in (summarise(trace, robot, gait.period_s), summarise(other, robot, None)):
            assert {k: summary[k] for k in KEYS} == {k: expected[k] for k in KEYS}
        assert np.array_equal(trace.position_rad, other.position_rad)


def test_the_engine_samples_every_cycle_of_the_runner_to_the_bit() -> None:
    """Open loop (chunks of cycles per rollout) and closed loop (keyframes that wait for the
    measured pose, one cycle per rollout): the batch trace is the runner's cycle records."""
    robot = load_robot("snake8")
    waiting = {"advance": "error", "durations": (0.3,), "error_threshold_rad": 0.05}
    for name, params in (("serpenoid", PARAMS[0]), ("keyframes", waiting)):
        records: list[CycleRecord] = []
        metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
        with TwinBackend(robot) as twin:
            run_gait(
                twin,
                make_gait(name, 8, params),
                SafetyLayer.for_robot(robot),
                RunPlan(1.2, ramp_out=False),
                metrics,
                observers=[records.append],
            )
        commands = GaitCommands([make_gait(name, 8, params)], robot)
        trace = TwinBatch(robot).run(commands, 1.2, 100.0)[0]
        assert commands.open_loop == (name == "serpenoid")
        assert trace.cycles == len(records) == 120
        assert np.array_equal(trace.time_s, [r.time_s for r in records])
        assert np.array_equal(trace.target_rad, [r.target_rad for r in records])
        assert np.array_equal(trace.command_rad, [r.command_rad for r in records])
        assert np.array_equal(trace.position_rad, [r.state.position_rad for r in records])
        assert np.array_equal(trace.effort_nm, [r.state.effort_nm for r in records])
        assert np.array_equal(trace.com_m, [r.body.com_m for r in records if r.body])


def test_hopeless_runs_stop_early_and_say_why() -> None:
    robot = load_robot("snake12")
    batch = TwinBatch(robot)
    envelope = Envelope.for_robot(robot, float(batch.start_com_m[2]))
    flying = dataclasses.replace(envelope, lift_limit_m=-1.0)  # every sample counts as flight
    gaits = [make_gait("sidewinding", 12)]
    trace = batch.run(GaitCommands(gaits, robot), 2.0, 100.0, envelope=flying)[0]
    assert trace.stop_reason == "airborne" and trace.cycles == 25
    upside_down = dataclasses.replace(envelope, rest_com_z_m=-1.0, lift_limit_m=10.0)
    upside_down = dataclasses.replace(upside_down, allow_roll=False)
    rolled = batch.run(
        GaitCommands([make_gait("rolling", 12)], robot), 2.0, 100.0, envelope=upside_down
    )[0]
    assert rolled.stop_reason in ("", "flipped")


def test_a_delayed_replay_from_a_bent_pose_starts_with_the_held_goals() -> None:
    robot = with_delay(load_robot("snake12"), 0.05)
    batch = TwinBatch(robot)
    pose = np.zeros(robot.joint_count)
    pose[0] = 0.5
    hold = ArrayCommands(np.broadcast_to(pose, (1, 10, robot.joint_count)))
    drift = []
    for past in (pose, np.zeros(robot.joint_count)):  # the goals held, or MjData's zeros
        start = batch.initial_state_with_pose(pose, past)
        trace = batch.run(hold, 0.1, 100.0, initial_state=start)[0]
        drift.append(float(np.abs(trace.position_rad[:, 0] - 0.5).max()))
    assert drift[0] < 1e-3 and drift[1] > 0.05  # zeros: the joint heads for 0 for 50 ms


def test_a_run_that_blows_up_at_the_floating_base_is_stopped_as_diverged_as_the_twin_raises() -> (
    None
):
    # Measured: the engine read mujoco.batch's warning field 0, mjWarningStat.lastinfo (the
    # index of the DOF that went bad), instead of field 1, the count. A blow-up first seen at
    # DOF 0 (the floating base, where a whole-body explosion shows first) left lastinfo at 0:
    # the run's records froze at the reset state and it scored as a full, healthy run.
    robot = load_robot("snake8")
    batch = TwinBatch(robot)
    data = mujoco.MjData(batch.model)
    mujoco.mj_setState(batch.model, data, batch.initial_state, STATE)
    data.qvel[0] = 1e11  # past MuJoCo's mjMAXVAL: a bad velocity at DOF 0 on the first step
    state = np.empty_like(batch.initial_state)
    mujoco.mj_getState(batch.model, data, state, STATE)
    gait = make_gait("serpenoid", 8, PARAMS[0])
    trace = batch.run(GaitCommands([gait], robot), 0.5, 100.0, initial_state=state)[0]
    assert trace.stop_reason == "diverged" and trace.cycles == 0
    with TwinBackend(robot) as twin:  # the step-by-step twin stops the same run
        mujoco.mj_setState(twin.model, twin.data, state, STATE)
        with pytest.raises(SimulationDivergedError):
            twin.advance(0.01)
