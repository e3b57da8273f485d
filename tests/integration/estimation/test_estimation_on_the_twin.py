"""The virtual chassis and the odometry on the twin, against its ground truth.

The estimator sees the cycle records only (joints with encoder noise, the head gyro and tilt);
the ground truth (link poses, centre of mass) is read from the twin's MjData by the test alone.
Each run is made once per module and shared.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.model_builder import link_name
from snakebot.cli.goto_options import steered_gait
from snakebot.config import RobotConfig
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.estimation import ChainGeometry, ChassisOdometry, OdometryConfig, VirtualChassis
from snakebot.session import Snake, load_robot, resolve_gait


def _noisy(robot: RobotConfig) -> RobotConfig:
    physics = robot.servo.physics
    extras = replace(physics.extras, encoder_noise_rad=0.003, quantise_encoder=1)
    return replace(robot, servo=replace(robot.servo, physics=replace(physics, extras=extras)))


@dataclass
class Run:
    """One twin run: per cycle the chassis from the measured joints in the world (through the
    true head pose), the true COM and true chassis yaw, and the odometry's estimate."""

    chassis_world: np.ndarray  # (T, 3, 3)
    true_com: np.ndarray  # (T, 3)
    true_yaw: np.ndarray  # (T,)
    estimate: np.ndarray  # (T, 3) x, y, yaw


def _run(robot_name: str, gait_name: str, duration_s: float = 20.0) -> Run:
    robot = _noisy(load_robot(robot_name))
    geometry = ChainGeometry.of_robot(robot)
    odometry = ChassisOdometry(geometry, OdometryConfig(radius_m=robot.link.radius_m))
    measured_chassis = VirtualChassis()
    true_chassis = VirtualChassis()
    rows: dict[str, list[np.ndarray]] = {"chassis": [], "com": [], "yaw": [], "estimate": []}
    with TwinBackend(robot, seed=2) as backend:
        links = [backend.model.body(link_name(i)).id for i in range(robot.link_count)]

        def observe(record: CycleRecord) -> None:
            data = backend.data
            frame = measured_chassis.update(geometry.module_centres(record.state.position_rad))
            head = data.xmat[links[0]].reshape(3, 3)
            rows["chassis"].append(head @ frame.rotation)
            x_axis = true_chassis.update(data.xipos[links]).rotation[:, 0]
            rows["yaw"].append(np.array(math.atan2(x_axis[1], x_axis[0])))
            rows["com"].append(data.subtree_com[links[0]].copy())
            pose = odometry.pose
            assert pose is not None
            rows["estimate"].append(np.array([pose.x_m, pose.y_m, pose.yaw_rad]))

        _, gait = resolve_gait(robot, gait_name)
        metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
        plan = RunPlan(duration_s, ramp_out=False)
        run_gait(
            backend,
            gait,
            SafetyLayer.for_robot(robot),
            plan,
            metrics,
            observers=[odometry, observe],
        )
    return Run(
        np.array(rows["chassis"]),
        np.array(rows["com"]),
        np.unwrap(np.array(rows["yaw"])),
        np.array(rows["estimate"]),
    )


@pytest.fixture(scope="module")
def sidewinding() -> Run:
    return _run("snake12", "sidewinding")


@pytest.fixture(scope="module")
def undulation() -> Run:
    return _run("snake8", "serpenoid", duration_s=10.0)


@pytest.mark.parametrize("which", ["sidewinding", "undulation"])
def test_the_chassis_axes_never_flip_between_cycles(
    which: str, request: pytest.FixtureRequest
) -> None:
    run: Run = request.getfixturevalue(which)
    dots = np.einsum("tij,tij->tj", run.chassis_world[1:], run.chassis_world[:-1])
    assert dots.min() > 0.9, np.argwhere(dots < 0.9)[:5]


def test_sidewinding_travels_along_a_fixed_direction_of_the_chassis(sidewinding: Run) -> None:
    period = 200  # cycles: one gait cycle (0.5 Hz at 100 Hz)
    angles = []
    for start in range(period, len(sidewinding.true_com) - period, period):
        step = sidewinding.true_com[start + period] - sidewinding.true_com[start]
        in_chassis = sidewinding.chassis_world[start].T @ step
        angles.append(math.degrees(math.atan2(in_chassis[1], in_chassis[0])))
    assert len(angles) >= 7
    assert np.ptp(angles) < 15.0, angles  # while the chassis itself turns (below)
    world = np.unwrap(
        np.arctan2(sidewinding.chassis_world[:, 1, 0], sidewinding.chassis_world[:, 0, 0])
    )
    assert abs(math.degrees(world[-1] - world[period])) > 15.0


def test_sidewinding_odometry_is_within_10_percent_and_10_degrees(sidewinding: Run) -> None:
    true_step = sidewinding.true_com[-1, :2] - sidewinding.true_com[0, :2]
    est_step = sidewinding.estimate[-1, :2] - sidewinding.estimate[0, :2]
    distance = float(np.linalg.norm(true_step))
    assert distance > 2.0  # 20 s of sidewinding goes somewhere
    assert np.linalg.norm(est_step - true_step) <= 0.10 * distance
    true_turn = sidewinding.true_yaw[-1] - sidewinding.true_yaw[0]
    est_turn = sidewinding.estimate[-1, 2] - sidewinding.estimate[0, 2]
    assert abs(math.degrees(est_turn - true_turn)) <= 10.0


def test_undulation_odometry_follows_the_snake(undulation: Run) -> None:
    true_step = undulation.true_com[-1, :2] - undulation.true_com[0, :2]
    est_step = undulation.estimate[-1, :2] - undulation.estimate[0, :2]
    distance = float(np.linalg.norm(true_step))
    assert distance > 1.0
    assert np.linalg.norm(est_step - true_step) <= 0.25 * distance


def test_run_to_a_point_ends_near_it_by_the_ground_truth() -> None:
    robot = load_robot("snake8")
    name, gait = resolve_gait(robot, "serpenoid")
    name, steered, steering = steered_gait(robot, name, gait, "1.5,0.5")
    with Snake.prepare(robot, "twin") as snake:
        backend = snake.backend
        assert isinstance(backend, TwinBackend)
        start = backend.body_state().com_m.copy()
        summary = snake.run(
            steered, duration_s=40.0, observers=[steering.odometry], stop=steering.reached
        )
        end = backend.body_state().com_m
    assert "reached the point" in str(summary.extra["stopped_by"])
    # The twin starts straight at the origin facing +x: the point is 1.5 m ahead, 0.5 m left.
    miss = np.hypot(*(end[:2] - start[:2] - np.array([1.5, 0.5])))
    assert miss <= 0.3
