"""The twin's readouts: each formula once, and every path that reads the twin reads the same."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.readouts import (
    WARNING_NUMBER,
    Capsules,
    StepCheck,
    positive_power_w,
    servo_torque_nm,
    unstable_count,
)
from snakebot.config import load_robot
from snakebot.errors import SimulationDivergedError
from snakebot.tuning.engine import twin_layout
from snakebot.types import JointCommand


@pytest.fixture(scope="module")
def twin() -> TwinBackend:
    backend = TwinBackend(load_robot("snake8"))
    backend.connect()
    return backend


def test_positive_power_counts_driven_joints_and_missing_values_as_nothing() -> None:
    effort = np.array([2.0, -1.0, 3.0, np.nan, 0.5])
    velocity = np.array([1.5, 2.0, -1.0, 1.0, 0.0])
    np.testing.assert_array_equal(positive_power_w(effort, velocity), [3.0, 0.0, 0.0, 0.0, 0.0])
    rows = positive_power_w(np.tile(effort, (3, 1)), np.tile(velocity, (3, 1)))
    assert rows.shape == (3, 5) and rows.sum() == 9.0


def test_the_twins_effort_is_the_servo_torque_readout_of_its_state(twin: TwinBackend) -> None:
    twin.send_command(JointCommand(np.full(8, 0.4)))
    twin.advance(0.05)
    state = twin.read_state()
    layout = twin_layout(twin.model, twin.robot)
    dof = layout.dof_index
    expected = servo_torque_nm(
        twin.data.actuator_force, twin.model.dof_damping[dof], twin.data.qvel[dof]
    )
    assert np.abs(state.effort_nm).max() > 0.01  # the joints are moving and loaded
    np.testing.assert_array_equal(state.effort_nm, expected)
    # the joints' damping brakes: the output torque is the drive less it
    assert not np.array_equal(state.effort_nm, twin.data.actuator_force)


def test_clearance_is_the_lowest_capsule_point_above_the_floor(twin: TwinBackend) -> None:
    model = twin.model
    data = mujoco.MjData(model)
    capsules = Capsules.of_modules(model, twin.robot.link_count)
    mujoco.mj_forward(model, data)
    lying = float(capsules.clearance_m(data.geom_xpos, data.geom_xmat))
    data.qpos[2] += 0.1  # lift the whole straight snake 10 cm
    mujoco.mj_forward(model, data)
    lifted = float(capsules.clearance_m(data.geom_xpos, data.geom_xmat))
    assert lifted - lying == pytest.approx(0.1, abs=1e-12)
    # stood on its head (capsule axes vertical): the lowest point is a half length lower
    data.qpos[3:7] = [math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0]
    mujoco.mj_forward(model, data)
    standing = float(capsules.clearance_m(data.geom_xpos, data.geom_xmat))
    centre_z = data.geom_xpos[capsules.geoms, 2].min()
    expected = centre_z - capsules.radius_m[0] - capsules.half_length_m[0]
    assert standing == pytest.approx(expected, abs=1e-12)
    # a batch's (B, K) samples at once give each sample's own clearance
    xpos = np.stack([data.geom_xpos, data.geom_xpos + np.array([0.0, 0.0, 0.2])])[:, None]
    xmat = np.stack([data.geom_xmat, data.geom_xmat])[:, None]
    batched = capsules.clearance_m(xpos, xmat)
    assert batched.shape == (2, 1)
    np.testing.assert_allclose(batched[:, 0], [standing, standing + 0.2], atol=1e-12)


def test_an_instability_counts_for_one_run_and_per_run_in_a_batch(twin: TwinBackend) -> None:
    model = twin.model
    data = mujoco.MjData(model)
    assert int(unstable_count(data.warning.number)) == 0
    data.qvel[0] = 1e11  # past mjMAXVAL at DOF 0: MuJoCo resets and counts it
    mujoco.mj_step(model, data)
    assert int(unstable_count(data.warning.number)) == 1
    # a batch's warnings are (B, nwarn, 2) of (lastinfo, number): the count is field 1
    warnings = np.zeros((3, len(data.warning), 2), dtype=np.int32)
    warnings[1, mujoco.mjtWarning.mjWARN_BADQVEL] = (0, 1)  # lastinfo 0: DOF 0 went bad
    warnings[2, mujoco.mjtWarning.mjWARN_BADQACC] = (5, 2)
    warnings[0, mujoco.mjtWarning.mjWARN_CONTACTFULL] = (7, 4)  # not an instability
    np.testing.assert_array_equal(unstable_count(warnings[..., WARNING_NUMBER]), [0, 1, 2])


def test_the_step_check_names_when_the_instability_happened_inside_the_steps(
    twin: TwinBackend,
) -> None:
    model = twin.model
    data = mujoco.MjData(model)
    check = StepCheck(model, data)
    mujoco.mj_step(model, data, 3)
    check.start()
    mujoco.mj_step(model, data, 2)
    check.finish(2)  # a credible step passes
    check.start()
    data.qvel[0] = 1e11
    mujoco.mj_step(model, data, 5)  # MuJoCo resets at the first of the 5 and steps on
    with pytest.raises(SimulationDivergedError) as caught:
        check.finish(5)
    assert caught.value.time_s == pytest.approx(5 * model.opt.timestep)
    # a position left non-finite counts where the caller asks for it (the soft body's friction
    # rule writes velocities between steps): without a MuJoCo warning
    check, strict = StepCheck(model, data), StepCheck(model, data, finite_positions=True)
    check.start()
    strict.start()
    data.qpos[0] = np.nan
    check.finish(0)
    with pytest.raises(SimulationDivergedError):
        strict.finish(0)
