"""Work and cost of transport are integrated over every physics step, not sampled per cycle.

The audit (issue 23): snake8 with P = D = 16383 reported 0.12 J at 100 Hz control and 3.8 J at
500 Hz for the same 10 s serpenoid, because effort times velocity was sampled once per control
period. Here one command sequence, held for 20 ms at a time, is played at 50, 100 and 500 Hz
control: the physics is the same, so the work must be the same, and equal to an integration of
torque times speed written out step by step in this file.
"""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.model_builder import joint_name
from snakebot.config import RobotConfig, load_robot
from snakebot.control.metrics import RunMetrics, cycle_work_j
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from snakebot.types import JointCommand
from tests.integration.twin.robots import with_gains

STIFF = with_gains(load_robot("snake8"), 16383, 16383)  # the audit's servo
HOLD_S = 0.02  # each command is held 20 ms: a whole number of periods at 50, 100 and 500 Hz
DURATION_S = 2.0


def commands(robot: RobotConfig) -> np.ndarray:
    """A travelling wave sampled every HOLD_S: (K, N) goals, rad."""
    times = np.arange(round(DURATION_S / HOLD_S)) * HOLD_S
    phase = 0.6 * np.arange(robot.joint_count)
    ramp = np.minimum(times / 0.5, 1.0)[:, None]
    return ramp * 0.6 * np.sin(2 * np.pi * 1.0 * times[:, None] - phase)


def play(robot: RobotConfig, rate_hz: float) -> tuple[float, float, float]:
    """The command sequence at ``rate_hz``: (work the metrics count, the health check's energy
    injected, the work RunMetrics would have sampled once per cycle) in J."""
    period = 1.0 / rate_hz
    repeats = round(HOLD_S / period)
    integrated = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    sampled = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    with TwinBackend(robot) as twin:
        before = twin.read_state()
        for goal in commands(robot):
            twin.send_command(JointCommand(goal))
            for _ in range(repeats):
                twin.advance(period)
                state = twin.read_state()
                integrated.add(goal, state, None, period, cycle_work_j(before, state))
                sampled.add(goal, state, None, period)
                before = state
        health = twin.physics_health()
    assert health is not None
    return integrated.positive_work_j, float(health["energy_injected_j"]), sampled.positive_work_j  # type: ignore[arg-type]


def step_by_step_work_j(robot: RobotConfig) -> float:
    """The same commands on a twin stepped here one ``mj_step`` at a time: Σ max(τ·ω, 0)·h with
    τ = actuator force - joint damping · ω (the servo's output torque), ω after the step."""
    import mujoco

    with TwinBackend(robot) as twin:
        model, data = twin.model, twin.data
        dofs = [model.jnt_dofadr[model.joint(joint_name(i)).id] for i in range(robot.joint_count)]
        steps = round(HOLD_S / model.opt.timestep)
        work = 0.0
        for goal in commands(robot):
            data.ctrl[:] = goal
            for _ in range(steps):
                mujoco.mj_step(model, data)
                for actuator, dof in enumerate(dofs):
                    speed = float(data.qvel[dof])
                    torque = float(data.actuator_force[actuator]) - model.dof_damping[dof] * speed
                    work += max(torque * speed, 0.0) * model.opt.timestep
    return work


@pytest.mark.parametrize("robot", [STIFF, load_robot("snake8")], ids=["P=D=16383", "default"])
def test_one_command_sequence_gives_the_same_work_at_50_100_and_500_hz(
    robot: RobotConfig,
) -> None:
    results = {rate: play(robot, rate) for rate in (50.0, 100.0, 500.0)}
    reference = step_by_step_work_j(robot)
    assert reference > 0.05
    for rate, (work, injected, _) in results.items():
        assert work == pytest.approx(reference, rel=1e-9), rate
        assert injected == pytest.approx(reference, rel=1e-9), rate
    works = [work for work, _, _ in results.values()]
    assert max(works) / min(works) - 1.0 < 0.02
    # 500 Hz is one physics step per cycle, where a sample is the integral; at 50 Hz sampling
    # once per cycle misses what the stiff servo does between samples (the audit's defect).
    sampled_50, sampled_500 = results[50.0][2], results[500.0][2]
    assert sampled_500 == pytest.approx(reference, rel=1e-9)
    if robot is STIFF:
        assert sampled_50 < 0.5 * reference


def test_a_run_counts_the_work_of_every_physics_step_of_its_scored_cycles() -> None:
    """`snakebot run`'s path: the summary's work is the twin's integral over the scored cycles
    and stays within the health check's (which also counts the ramp-out)."""
    metrics = RunMetrics(STIFF.joint_count, STIFF.body_length_m, STIFF.total_mass_kg)
    with TwinBackend(STIFF) as twin:
        result = run_gait(
            twin,
            make_gait("serpenoid", STIFF.joint_count),
            SafetyLayer.for_robot(STIFF),
            RunPlan(duration_s=2.0, rate_hz=100.0, ramp_out=False),
            metrics,
        )
        total = float(twin.read_state().positive_work_j.sum())  # type: ignore[union-attr]
    assert result.summary["positive_work_j"] == pytest.approx(total, rel=1e-9)
    assert result.summary["cost_of_transport"] == pytest.approx(
        total / (STIFF.total_mass_kg * 9.81 * float(result.summary["distance_m"])),  # type: ignore[arg-type]
        rel=1e-9,
    )


def test_the_python_fallback_integrates_the_same_bits_as_the_c_loop() -> None:
    """Without a compiler the twin steps one mj_step per call and integrates with numpy
    (readouts.step_work_j); the work and the state are the compiled period's to the bit."""
    ends = []
    for compiled in (True, False):
        with TwinBackend(STIFF) as twin:
            if not compiled:
                twin._period = None
            for goal in commands(STIFF)[:30]:
                twin.send_command(JointCommand(goal))
                twin.advance(0.01)
            state = twin.read_state()
            assert state.positive_work_j is not None
            ends.append((state.positive_work_j.tobytes(), twin.data.qpos.tobytes()))
    assert ends[0] == ends[1]
