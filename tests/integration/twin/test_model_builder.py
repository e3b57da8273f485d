from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from snakebot.backends.twin import GroundFriction, TwinBackend, build_model
from snakebot.config import load_robot
from snakebot.errors import ConfigError, SimulationDivergedError
from snakebot.servo.dynamics import servo_dynamics
from snakebot.types import JointCommand
from tests.integration.twin.robots import robot_with_joints, with_gains


@pytest.mark.parametrize("joints", [2, 5, 16, 33, 64])
def test_model_size_follows_the_config(joints: int) -> None:
    model, _ = build_model(robot_with_joints(joints))
    assert model.nu == joints
    assert model.njnt == joints + 1  # the free root plus one hinge per servo
    assert model.nbody == joints + 2  # world + modules
    assert model.npair == joints + 1  # one capsule-floor pair per module
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST


@pytest.mark.parametrize("name", ["snake8", "snake12"])
def test_shipped_robot_compiles_and_steps(name: str) -> None:
    robot = load_robot(name)
    with TwinBackend(robot) as twin:
        for _ in range(50):
            twin.send_command(JointCommand(np.full(robot.joint_count, 0.2)))
            twin.advance(0.01)
        state = twin.read_state()
    assert state.time_s == pytest.approx(0.5)
    assert np.isfinite(state.position_rad).all()
    # Every joint moved towards the goal; the ground load leaves a P-controller some error.
    assert np.all(state.position_rad > 0.05) and np.all(state.position_rad < 0.25)


def test_servo_limits_come_from_the_datasheet() -> None:
    robot = load_robot("snake8")
    model, _ = build_model(robot)
    servo = servo_dynamics(robot.servo.physics, robot.gains)
    assert model.actuator_forcerange[0].tolist() == pytest.approx([-1.4, 1.4])
    # back-EMF damping = stall torque / no-load speed: the torque-speed line of the datasheet
    assert model.dof_damping[6] == pytest.approx(1.4 / 5.969 + 0.004)
    assert model.dof_armature[6] == pytest.approx(0.002)
    assert model.jnt_range[1].tolist() == pytest.approx([-1.5, 1.5])
    assert (
        servo.torque_limit_nm / servo.back_emf_damping_nms < robot.servo.physics.no_load_speed_rad_s
    )


def test_unloaded_joint_never_beats_no_load_speed() -> None:
    robot = robot_with_joints(2)
    with TwinBackend(robot, friction=GroundFriction(0.0, 0.0)) as twin:
        twin.send_command(JointCommand(np.array([1.5, -1.5])))
        peak = 0.0
        for _ in range(40):
            twin.advance(0.01)
            peak = max(peak, float(np.abs(twin.read_state().velocity_rad_s).max()))
    assert 2.0 < peak <= robot.servo.physics.no_load_speed_rad_s * 1.02


def _drag_friction(direction: np.ndarray, friction: GroundFriction) -> float:
    """Effective friction coefficient of a straight, stiff snake pushed with 1.5 m g."""
    robot = robot_with_joints(4)
    with TwinBackend(robot, friction=friction) as twin:
        model, data = twin.model, twin.data
        mass = robot.total_mass_kg
        twin.advance(0.1)
        v0 = data.qvel[:2].copy()
        push = 1.5 * mass * 9.81
        for body in range(1, model.nbody):
            data.xfrc_applied[body, :2] = direction * push * model.body_mass[body] / mass
        twin.advance(0.3)
        accel = (data.qvel[:2] - v0) @ direction / 0.3
    return float((push - mass * accel) / (mass * 9.81))


def test_friction_is_anisotropic_along_and_across_links() -> None:
    friction = GroundFriction(axial=0.1, lateral=1.0)
    along = _drag_friction(np.array([1.0, 0.0]), friction)
    across = _drag_friction(np.array([0.0, 1.0]), friction)
    assert along == pytest.approx(0.1, abs=0.03)
    assert across == pytest.approx(1.0, abs=0.12)
    isotropic = GroundFriction(0.5, 0.5)
    assert _drag_friction(np.array([1.0, 0.0]), isotropic) == pytest.approx(
        _drag_friction(np.array([0.0, 1.0]), isotropic), abs=0.05
    )


def test_non_adjacent_links_collide() -> None:
    robot = robot_with_joints(4)
    with TwinBackend(robot, friction=GroundFriction(0.5, 0.5)) as twin:
        twin.send_command(JointCommand(np.array([1.5, 1.5, 1.5, 1.5])))
        for _ in range(100):
            twin.advance(0.01)
        model, data = twin.model, twin.data
        floor = model.geom("floor").id
        link_contacts = [
            (model.geom_bodyid[c.geom1], model.geom_bodyid[c.geom2])
            for c in data.contact[: data.ncon]
            if floor not in (c.geom1, c.geom2)
        ]
    assert link_contacts, "folding the snake onto itself made no self-contact"
    assert all(abs(int(a) - int(b)) > 1 for a, b in link_contacts)


@pytest.mark.parametrize("timestep", [0.002, 0.005])
def test_highest_gains_stay_stable(timestep: float) -> None:
    robot = with_gains(load_robot("snake12"), p=16383, d=16383)
    with TwinBackend(robot, timestep_s=timestep) as twin:
        for k in range(300):
            t = k * 0.01
            twin.send_command(JointCommand(0.8 * np.sin(3 * t - 0.6 * np.arange(12))))
            twin.advance(0.01)
        state = twin.read_state()
    assert np.isfinite(state.position_rad).all()
    assert np.abs(state.velocity_rad_s).max() < 10


def test_divergence_raises_a_typed_error() -> None:
    with TwinBackend(load_robot("snake8")) as twin:
        twin.data.qvel[6] = 1e12
        with pytest.raises(SimulationDivergedError, match="diverged at t="):
            twin.advance(0.01)


def test_control_period_must_be_whole_steps() -> None:
    with TwinBackend(load_robot("snake8")) as twin, pytest.raises(ValueError, match="whole number"):
        twin.advance(0.003)


def test_friction_option_parsing() -> None:
    assert GroundFriction.parse("0.02,1.0") == GroundFriction(0.02, 1.0)
    # Three numbers are the scale model's forward, backward, lateral.
    assert GroundFriction.parse("0.05,0.5,1") == GroundFriction(0.05, 1.0, 0.5)
    for bad in ["0.1", "a,b", "-1,1", "1,2,3,4", "0.5,0.1,1"]:
        with pytest.raises(ConfigError, match=r"^friction: "):
            GroundFriction.parse(bad)


def test_exported_model_loads_in_mujoco(tmp_path: Path) -> None:
    _, spec = build_model(load_robot("snake12"))
    path = tmp_path / "snake12.xml"
    path.write_text(spec.to_xml())
    model = mujoco.MjModel.from_xml_path(str(path))
    assert model.nu == 12 and model.npair == 13
