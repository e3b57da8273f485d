"""The twin's measured effort is the servo torque of the state it is read in.

The twin computes each servo's torque once a control period (the physics check needs it after
the step) and hands that value to ``read_state``; these tests hold that the effort a user reads
is always the torque of the physics and gains as they are at that moment.
"""

from __future__ import annotations

import numpy as np

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.readouts import servo_torque_nm
from snakebot.config import load_robot
from snakebot.types import JointCommand, PDGains

ROBOT = load_robot("snake8")


def torque_now(twin: TwinBackend) -> np.ndarray:
    """The servo torque of the twin's MuJoCo state and model now, from the readout formula."""
    dof = twin._dof_index
    return servo_torque_nm(
        twin.data.actuator_force, twin.model.dof_damping[dof], twin.data.qvel[dof]
    )


def moving(twin: TwinBackend) -> None:
    """A few cycles of a travelling wave, so velocities and torques are not zero."""
    phase = 0.7 * np.arange(ROBOT.joint_count)
    for k in range(20):
        twin.send_command(JointCommand(0.5 * np.sin(np.pi * k / 25 - phase)))
        twin.advance(0.01)


def test_effort_after_a_period_is_the_torque_of_that_state() -> None:
    with TwinBackend(ROBOT) as twin:
        moving(twin)
        state = twin.read_state()
        assert np.abs(state.effort_nm).max() > 0.01
        assert state.effort_nm.tobytes() == torque_now(twin).tobytes()
        again = twin.read_state()  # a second read: the same values, its own array
        assert again.effort_nm.tobytes() == state.effort_nm.tobytes()
        again.effort_nm[:] = 0.0
        assert state.effort_nm.tobytes() == torque_now(twin).tobytes()


def test_effort_follows_a_gain_or_torque_change_made_after_the_step() -> None:
    with TwinBackend(ROBOT) as twin:
        moving(twin)
        stepped = torque_now(twin)
        twin.set_torque(False)  # limp: the back-EMF damping is gone, friction remains
        limp = twin.read_state().effort_nm
        assert limp.tobytes() == torque_now(twin).tobytes()
        assert not np.array_equal(limp, stepped)
        moving(twin)
        twin.set_torque(True)
        twin.set_gains(PDGains(kp_nm_per_rad=0.5, kd_nms_per_rad=0.01))
        assert twin.read_state().effort_nm.tobytes() == torque_now(twin).tobytes()


def test_effort_after_a_reset_is_the_reset_state_s() -> None:
    with TwinBackend(ROBOT) as twin:
        moving(twin)
        state = twin.reset()
        assert state.time_s == 0.0
        assert state.effort_nm.tobytes() == torque_now(twin).tobytes()
        assert np.abs(state.velocity_rad_s).max() == 0.0
