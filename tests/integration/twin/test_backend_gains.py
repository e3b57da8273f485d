"""TwinBackend gains per joint: the position actuators' kp/kv, and limp joints stay limp."""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.model_builder import joint_name
from snakebot.backends.twin.servo_model import servo_dynamics
from snakebot.config import RobotConfig, load_robot
from snakebot.types import ServoGains

SOFT = ServoGains(position_p=100, position_d=500)


def kp_kv(twin: TwinBackend) -> tuple[np.ndarray, np.ndarray]:
    model = twin.model
    kp = model.actuator_gainprm[:, 0].copy()
    assert np.array_equal(model.actuator_biasprm[:, 1], -kp)  # set_to_position's layout
    return kp, -model.actuator_biasprm[:, 2].copy()


def expected(robot: RobotConfig, gains: ServoGains, twin: TwinBackend) -> tuple[float, float]:
    servo = servo_dynamics(robot.servo.physics, gains)
    return servo.stiffness_nm_per_rad, servo.actuator_kv(float(twin.model.opt.timestep))


def test_joint_gains_change_only_the_chosen_joints() -> None:
    robot = load_robot("snake8")
    twin = TwinBackend(robot)
    with twin:
        base, soft = expected(robot, robot.gains, twin), expected(robot, SOFT, twin)
        twin.set_joint_gains([1, 6], SOFT)
        twin.set_joint_gains(np.arange(8) == 3, SOFT)  # a mask selects too
        kp, kv = kp_kv(twin)
        chosen = np.isin(np.arange(8), [1, 3, 6])
        assert kp == pytest.approx(np.where(chosen, soft[0], base[0]))
        assert kv == pytest.approx(np.where(chosen, soft[1], base[1]))
        twin.set_gains(robot.gains)  # all joints again
        assert kp_kv(twin)[0] == pytest.approx(np.full(8, base[0]))


def test_a_joint_with_torque_off_stays_limp_and_keeps_its_gains_for_later() -> None:
    robot = load_robot("snake8")
    twin = TwinBackend(robot)
    with twin:
        twin.set_joint_torque(np.arange(8) != 2)
        twin.set_joint_gains(2, SOFT)
        kp, kv = kp_kv(twin)
        dof = twin.model.joint(joint_name(2)).dofadr[0]
        assert kp[2] == 0.0 and kv[2] == 0.0
        assert twin.model.dof_damping[dof] == robot.servo.physics.viscous_damping_nms
        twin.set_torque(True)
        kp, kv = kp_kv(twin)
        assert (kp[2], kv[2]) == pytest.approx(expected(robot, SOFT, twin))
        assert kp[0] == pytest.approx(expected(robot, robot.gains, twin)[0])


def test_position_i_changes_nothing() -> None:
    robot = load_robot("snake8")
    twin = TwinBackend(robot)
    with twin:
        before = kp_kv(twin)
        twin.set_joint_gains(0, ServoGains(robot.gains.position_p, 900, robot.gains.position_d))
        after = kp_kv(twin)
        assert np.array_equal(before[0], after[0]) and np.array_equal(before[1], after[1])
