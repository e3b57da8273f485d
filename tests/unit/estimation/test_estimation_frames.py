"""Forward kinematics and the virtual chassis on shapes made here (no physics)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from snakebot.backends.twin.model_builder import build_model, joint_name, link_name
from snakebot.estimation import ChainGeometry, VirtualChassis
from snakebot.estimation.odometry import (
    OdometryConfig,
    gravity_up_in_head,
    heading_rate,
    rotation_to_quat,
)
from snakebot.session import load_robot, resolve_gait


@pytest.mark.parametrize("name", ["snake12", "snake8"])
def test_module_centres_are_the_twins_link_centres(name: str) -> None:
    robot = load_robot(name)
    model, _ = build_model(robot)
    data = mujoco.MjData(model)
    joints = [model.jnt_qposadr[model.joint(joint_name(i)).id] for i in range(robot.joint_count)]
    links = [model.body(link_name(i)).id for i in range(robot.link_count)]
    geometry = ChainGeometry.of_robot(robot)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = rng.uniform(-1.0, 1.0, robot.joint_count)
        data.qpos[joints] = q
        mujoco.mj_kinematics(model, data)
        head = data.xmat[links[0]].reshape(3, 3)
        expected = (data.xipos[links] - data.xpos[links[0]]) @ head
        np.testing.assert_allclose(geometry.module_centres(q), expected, atol=1e-9)


def test_a_straight_body_takes_the_heads_axes() -> None:
    geometry = ChainGeometry(0.1, ("yaw", "pitch") * 3)
    frame = VirtualChassis().update(geometry.module_centres(np.zeros(6)))
    np.testing.assert_allclose(frame.rotation, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(frame.origin_m, [-0.35, 0.0, 0.0])
    assert frame.extent_m[1] == pytest.approx(0.0, abs=1e-12)


def test_the_frame_is_the_principal_axes_with_x_toward_the_head() -> None:
    rng = np.random.default_rng(1)
    points = rng.normal(size=(9, 3)) * [1.0, 0.3, 0.05]
    points[0] = [3.0, 0.0, 0.0]  # the head, far out along +x
    frame = VirtualChassis().update(points)
    assert frame.rotation[0, 0] > 0.9  # x along the long axis, toward the head
    assert frame.extent_m[0] > frame.extent_m[1] > frame.extent_m[2]
    np.testing.assert_allclose(frame.rotation.T @ frame.rotation, np.eye(3), atol=1e-12)
    assert np.linalg.det(frame.rotation) == pytest.approx(1.0)
    np.testing.assert_allclose(frame.to_chassis(points), frame.positions_m, atol=1e-12)


def test_commanded_sidewinding_never_flips_the_frame() -> None:
    robot = load_robot("snake12")
    geometry = ChainGeometry.of_robot(robot)
    _, gait = resolve_gait(robot, "sidewinding")
    chassis = VirtualChassis()
    last = None
    for t in np.arange(0.0, 8.0, 0.01):
        ramp = min(1.0, t / 1.0)
        frame = chassis.update(geometry.module_centres(gait.targets(float(t)) * ramp))
        if last is not None and frame.extent_m[1] > 1e-3:
            # the module coordinates on every axis change little from a cycle to the next
            for axis in range(3):
                mine, before = frame.positions_m[:, axis], last.positions_m[:, axis]
                assert mine @ before > 0, (t, axis)
        last = frame


def test_bad_inputs_raise() -> None:
    with pytest.raises(ValueError, match="yaw or pitch"):
        ChainGeometry(0.1, ("roll",))
    with pytest.raises(ValueError, match="joint angles"):
        ChainGeometry(0.1, ("yaw",)).frames(np.zeros(2))
    with pytest.raises(ValueError, match="module positions"):
        VirtualChassis().update(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="slip"):
        OdometryConfig(slip="skate")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="contact_modules"):
        OdometryConfig(contact_modules=1)


def _quat(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = axis / np.linalg.norm(axis)
    return np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * axis])


def _matrix(quat: np.ndarray) -> np.ndarray:
    out = np.zeros(9)
    mujoco.mju_quat2Mat(out, quat)
    return out.reshape(3, 3)


def test_gravity_and_quaternions_round_trip() -> None:
    quat = _quat(np.array([0.3, -0.5, 0.8]), 1.1)
    rotation = _matrix(quat)
    np.testing.assert_allclose(gravity_up_in_head(quat), rotation.T @ [0, 0, 1], atol=1e-12)
    back = rotation_to_quat(rotation)
    np.testing.assert_allclose(back, quat if quat[0] >= 0 else -quat, atol=1e-12)


def test_the_heading_rate_is_the_heading_s_derivative() -> None:
    # A pitched head turning about a tilted axis: the heading of its x axis moves faster or
    # slower than the rate about up, as the formula says.
    start = _matrix(_quat(np.array([0.2, 1.0, 0.1]), 0.6))
    omega_head = np.array([0.4, -0.7, 0.9])
    dt = 1e-6

    def heading(rotation: np.ndarray) -> float:
        return math.atan2(rotation[1, 0], rotation[0, 0])

    speed = float(np.linalg.norm(omega_head))
    later = np.zeros(4)
    mujoco.mju_axisAngle2Quat(later, omega_head / speed, speed * dt)
    after = start @ _matrix(later)
    numeric = (heading(after) - heading(start)) / dt
    up = start.T @ np.array([0.0, 0.0, 1.0])
    assert heading_rate(omega_head, up) == pytest.approx(numeric, rel=1e-4)
    assert abs(float(omega_head @ up) - numeric) > 0.05  # the naive rate would be wrong here
