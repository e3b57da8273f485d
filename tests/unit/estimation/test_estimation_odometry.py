"""The odometry and the steering on joint angles made here (no physics)."""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.estimation import ChainGeometry, ChassisOdometry, OdometryConfig
from snakebot.estimation.goto import GoToPoint, SteeringConfig
from snakebot.estimation.odometry import gravity_up_in_head
from snakebot.session import load_robot, resolve_gait


def test_no_pose_before_the_first_cycle_and_the_start_is_the_heads_frame() -> None:
    geometry = ChainGeometry(0.1, ("yaw",) * 4)
    odometry = ChassisOdometry(geometry)
    assert odometry.body_state() is None and odometry.pose is None
    pose = odometry.update(0.0, np.zeros(4))
    body = odometry.body_state()
    assert body is not None
    np.testing.assert_allclose(body.com_m[:2], [-0.25, 0.0], atol=1e-12)  # 5 modules behind
    np.testing.assert_allclose(body.head_quat, [1.0, 0.0, 0.0, 0.0], atol=1e-12)
    assert pose.yaw_rad == pytest.approx(0.0) and odometry.slip == "no_lateral_slip"


def test_a_body_that_holds_its_shape_stays_where_it_is() -> None:
    geometry = ChainGeometry(0.065, ("yaw", "pitch") * 6)
    odometry = ChassisOdometry(geometry)
    shape = np.random.default_rng(0).uniform(-0.5, 0.5, 12)
    first = odometry.update(0.0, shape)
    for k in range(1, 50):
        last = odometry.update(0.01 * k, shape)
    assert (last.x_m, last.y_m, last.yaw_rad) == pytest.approx(
        (first.x_m, first.y_m, first.yaw_rad), abs=1e-9
    )
    assert odometry.slip == "static"


def test_up_stays_up_while_noise_is_all_the_shape_there_is() -> None:
    # A straight 12-module chain read through 3 mrad of encoder noise: its cross extents are
    # noise, and the ground's normal must not follow them (it once turned upside down).
    geometry = ChainGeometry(0.065, ("yaw", "pitch") * 6)
    odometry = ChassisOdometry(geometry)
    rng = np.random.default_rng(4)
    for k in range(100):
        odometry.update(0.01 * k, rng.normal(0.0, 0.003, 12))
        body = odometry.body_state()
        assert body is not None
        assert gravity_up_in_head(body.head_quat)[2] > 0.99, k


def test_commanded_sidewinding_does_not_turn_the_estimate_upside_down() -> None:
    robot = load_robot("snake12")
    _, gait = resolve_gait(robot, "sidewinding")
    odometry = ChassisOdometry(ChainGeometry.of_robot(robot), OdometryConfig())
    for t in np.arange(0.0, 4.0, 0.01):
        odometry.update(float(t), gait.targets(float(t)) * min(1.0, float(t)))
        body = odometry.body_state()
        assert body is not None
        head_up = gravity_up_in_head(body.head_quat)
        assert head_up[2] > -0.5  # the head rolls with the wave, never onto its back


def test_steering_turns_toward_the_point_and_stops_near_it() -> None:
    robot = load_robot("snake8")
    _, gait = resolve_gait(robot, "serpenoid")
    odometry = ChassisOdometry(ChainGeometry.of_robot(robot))
    steering = GoToPoint(gait, odometry, (0.0, 1.0), np.ones(8, dtype=bool), SteeringConfig())
    np.testing.assert_array_equal(steering.command(0.0), gait.command(0.0))  # no pose yet
    odometry.update(0.0, np.zeros(8))
    for k in range(1, 200):
        steering.command(0.01 * k)
    # The point is to the left: the serpenoid turns left with a negative offset.
    assert steering.offset_rad == pytest.approx(-SteeringConfig().max_offset_rad)
    assert steering.reached() is None
    far = steering.distance_m()
    assert far == pytest.approx(1.0)  # from the centre of mass, which has not moved
    with pytest.raises(ValueError, match="yaw_mask"):
        GoToPoint(gait, odometry, (1.0, 0.0), np.ones(3, dtype=bool))
    with pytest.raises(ValueError, match="coast_s"):
        SteeringConfig(coast_s=-1.0)
