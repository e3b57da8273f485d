"""The twin shows the physics the seeds describe (issue 2, "Done when"); numbers in docs/twin.md."""

from __future__ import annotations

import math

import pytest
from scipy.special import j0

from snakebot.backends.twin import GroundFriction, TwinBackend
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait

pytestmark = pytest.mark.slow


def run(
    robot_name: str,
    gait: str,
    seconds: float,
    friction: GroundFriction | None = None,
    **params: object,
) -> dict[str, object]:
    robot = load_robot(robot_name)
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    roll = [0.0, 0.0]  # unwrapped head roll about its own axis, last wrapped value

    with TwinBackend(robot, friction=friction) as twin:
        head = twin.model.body("link0").id

        def track_roll(cycle: int, gait_time_s: float) -> None:
            matrix = twin.data.xmat[head]
            angle = math.atan2(matrix[7], matrix[8])  # roll from the rotation matrix (ZYX)
            roll[0] += math.remainder(angle - roll[1], 2 * math.pi)
            roll[1] = angle

        result = run_gait(
            twin,
            make_gait(gait, robot.joint_count, params),
            SafetyLayer.for_robot(robot),
            RunPlan(duration_s=seconds),
            metrics,
            on_cycle=track_roll,
        )
    result.summary["head_roll_turns"] = roll[0] / (2 * math.pi)
    return result.summary


def no_slip_distance_per_cycle(robot_name: str, amplitude: float, phase_lag: float) -> float:
    """Kinematic serpenoid bound (L/K) J0(a) (locomotion.md §1.1)."""
    robot = load_robot(robot_name)
    waves = robot.link_count * phase_lag / (2 * math.pi)
    winding = amplitude / (2 * math.sin(phase_lag / 2))
    return float(robot.body_length_m / waves * j0(winding))


SERPENOID = {"amplitude": 0.4, "omega": math.pi, "phase_lag": 0.7}


def test_head_to_tail_wave_moves_snake8_head_first_near_the_no_slip_bound() -> None:
    summary = run("snake8", "serpenoid", 20.0, GroundFriction(0.02, 1.0), **SERPENOID)
    assert abs(float(summary["heading_deg"])) < 15  # head first: the head points along +x
    per_cycle = float(summary["distance_m"]) / float(summary["cycles"])
    bound = no_slip_distance_per_cycle("snake8", SERPENOID["amplitude"], SERPENOID["phase_lag"])
    assert per_cycle >= 0.8 * bound


def test_isotropic_ground_is_several_times_slower() -> None:
    strong = run("snake8", "serpenoid", 10.0, GroundFriction(0.02, 1.0), **SERPENOID)
    isotropic = run("snake8", "serpenoid", 10.0, GroundFriction(1.0, 1.0), **SERPENOID)
    assert float(isotropic["distance_m"]) * 3 < float(strong["distance_m"])


def test_snake12_sidewinds_sideways_on_isotropic_ground() -> None:
    summary = run("snake12", "sidewinding", 20.0)
    assert float(summary["body_lengths_per_cycle"]) >= 0.3
    assert 45 <= abs(float(summary["heading_deg"])) <= 135  # sideways to the body axis


def test_snake12_rolling_rolls() -> None:
    summary = run("snake12", "rolling", 10.0)
    # Five gait cycles: the body turns about its own axis, turn after turn, and moves sideways.
    assert abs(float(summary["head_roll_turns"])) >= 2
    assert float(summary["distance_m"]) > 0.05
    assert 45 <= abs(float(summary["heading_deg"])) <= 135
