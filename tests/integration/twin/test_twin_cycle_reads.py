"""The twin's per-cycle reads (views made once at connect) follow the physics after every step,
gain change and reset: what read_state and body_state report is what MjData holds now."""

from __future__ import annotations

import mujoco
import numpy as np

from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.types import JointCommand, PDGains


def _fresh_reads(twin: TwinBackend) -> tuple[np.ndarray, ...]:
    model, data, head = twin.model, twin.data, twin._head_id
    dof = twin._dof_index
    velocity = np.zeros(6)
    mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_BODY, head, velocity, 0)
    gyro = velocity[:3] @ data.xmat[head].reshape(3, 3)
    torque = data.actuator_force - model.dof_damping[dof] * data.qvel[dof]
    return (
        data.qpos[twin._qpos_index].copy(),
        data.qvel[dof].copy(),
        torque,
        data.subtree_com[head].copy(),
        data.xquat[head].copy(),
        gyro,
    )


def test_reads_follow_steps_gain_changes_and_reset() -> None:
    robot = load_robot("snake8")
    with TwinBackend(robot) as twin:
        pose = np.linspace(-0.4, 0.4, twin.joint_count)
        for step in range(30):
            if step == 10:
                twin.set_gains(
                    PDGains(robot.gains.kp_nm_per_rad * 0.5, robot.gains.kd_nms_per_rad * 2.0)
                )
            if step == 20:
                twin.reset(np.zeros(twin.joint_count))
            twin.send_command(JointCommand(pose * (1 if step % 2 else -1)))
            twin.advance(0.01)
            state, body = twin.read_state(), twin.body_state()
            position, velocity, torque, com, quat, gyro = _fresh_reads(twin)
            np.testing.assert_array_equal(state.position_rad, position)
            np.testing.assert_array_equal(state.velocity_rad_s, velocity)
            np.testing.assert_array_equal(state.effort_nm, torque)
            np.testing.assert_array_equal(body.com_m, com)
            np.testing.assert_array_equal(body.head_quat, quat)
            assert body.head_gyro_rad_s is not None
            np.testing.assert_array_equal(body.head_gyro_rad_s, gyro)
            assert np.abs(velocity).max() > 0.0  # it moves: a stale read would show
        # What was handed out is a copy: the next step does not change it.
        twin.advance(0.01)
        np.testing.assert_array_equal(state.position_rad, position)
        np.testing.assert_array_equal(body.com_m, com)
