"""TwinBackend gains per joint: the position actuators' kp/kv, and limp joints stay limp."""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.model_builder import joint_name
from snakebot.config import RobotConfig, load_robot
from snakebot.config.schema import GainRegisters
from snakebot.servo.dynamics import servo_dynamics
from snakebot.types import PDGains

SOFT = load_robot("snake8").servo.gains_of(GainRegisters(position_p=100, position_d=500))


def kp_kv(twin: TwinBackend) -> tuple[np.ndarray, np.ndarray]:
    model = twin.model
    kp = model.actuator_gainprm[:, 0].copy()
    assert np.array_equal(model.actuator_biasprm[:, 1], -kp)  # set_to_position's layout
    return kp, -model.actuator_biasprm[:, 2].copy()


def expected(robot: RobotConfig, gains: PDGains, twin: TwinBackend) -> tuple[float, float]:
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


def test_the_twin_takes_si_gains_as_they_are() -> None:
    # No register arithmetic between the contract and MuJoCo: kp is the stiffness asked for
    # (times sysid's stiffness_scale, 1 here) and kv the damping plus the stable-PD term.
    robot = load_robot("snake8")
    assert robot.servo.physics.stiffness_scale == 1.0
    twin = TwinBackend(robot)
    with twin:
        twin.set_joint_gains(0, PDGains(kp_nm_per_rad=2.5, kd_nms_per_rad=0.04))
        kp, kv = kp_kv(twin)
        timestep = float(twin.model.opt.timestep)
        assert kp[0] == 2.5
        assert kv[0] == pytest.approx(0.04 + timestep * 2.5, rel=1e-12)


def test_the_robot_files_register_gains_reach_the_twin_in_si() -> None:
    # snake8's [gains] P = 640: 1.4 N·m stall * (4096 / 2 pi) / (256 * 885) per unit of P.
    robot = load_robot("snake8")
    assert robot.gains.kp_nm_per_rad == pytest.approx(1.4 * 4096 / (2 * np.pi) / (256 * 885) * 640)
    with TwinBackend(robot) as twin:
        assert kp_kv(twin)[0] == pytest.approx(np.full(8, robot.gains.kp_nm_per_rad), rel=1e-12)
