"""The soft body behind the Backend contract: real MuJoCo, real lattice."""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np
import pytest

from snakebot.backends.softbody import SoftBodyBackend, build_body_spec
from snakebot.config.body_loader import body_names, load_body
from snakebot.errors import ConfigError, SimulationDivergedError
from snakebot.types import JointCommand, PDGains


@pytest.mark.parametrize("name", ["worm", "snake", "caterpillar", "snake_yawpitch"])
def test_every_shipped_body_compiles_steps_and_rests(name: str) -> None:
    assert name in body_names()
    body = load_body(name)
    with SoftBodyBackend(body) as backend:
        for _ in range(50):
            backend.advance(0.01)
        state = backend.read_state()
        com = backend.body_state().com_m
    assert state.position_rad.shape == (body.joint_count,)
    np.testing.assert_allclose(state.position_rad, 0.0, atol=0.01)  # resting straight
    assert state.time_s == pytest.approx(0.5)
    resting = body.lattice.height_m / 2 + body.lattice.point_radius_m
    assert com[2] == pytest.approx(resting, abs=2e-3)


def test_commanded_bends_and_contractions_are_measured_back() -> None:
    body = load_body("worm")
    sign = np.where(np.arange(body.lattice.segments) % 2, -1.0, 1.0)
    goal = np.stack((0.3 * sign, 0.1 * sign, 0.25 * sign), axis=1).reshape(-1)
    with SoftBodyBackend(body) as backend:
        backend.send_command(JointCommand(goal))
        for _ in range(100):
            backend.advance(0.01)
        state = backend.read_state()
    np.testing.assert_allclose(state.position_rad, goal, atol=0.04)
    np.testing.assert_allclose(state.velocity_rad_s, 0.0, atol=0.05)


def test_torque_off_relaxes_to_the_rest_shape_and_limp_close_stays_relaxed() -> None:
    body = load_body("worm")
    body = replace(body, safety=replace(body.safety, stop_policy="limp"))
    # The muscles alone: no floor friction, no scales holding the body back.
    backend = SoftBodyBackend(body, friction=0.0, directional=False)
    with backend:
        command = np.zeros(body.joint_count)
        command[0::3] = 0.3  # curl into an arc of yaw bends
        backend.send_command(JointCommand(command))
        for _ in range(100):
            backend.advance(0.01)
        bent = backend.read_state().position_rad[0::3]
        backend.set_torque(False)
        for _ in range(100):
            backend.advance(0.01)
        relaxed = backend.read_state().position_rad
    np.testing.assert_allclose(bent, 0.3, atol=0.03)
    np.testing.assert_allclose(relaxed, 0.0, atol=0.02)
    assert not backend.torque_enabled


def test_gains_change_nothing_in_a_mass_spring_muscle() -> None:
    body = load_body("worm")
    goal = np.tile([0.2, 0.0, 0.1], body.lattice.segments)

    def settle(gains: PDGains | None) -> np.ndarray:
        with SoftBodyBackend(body) as backend:
            if gains is not None:
                backend.set_gains(gains)
                assert backend.gains == gains
            backend.send_command(JointCommand(goal))
            for _ in range(30):
                backend.advance(0.01)
            return backend.read_state().position_rad

    np.testing.assert_array_equal(settle(None), settle(PDGains(kp_nm_per_rad=0.2)))


def test_efforts_times_velocities_are_the_muscles_power() -> None:
    body = load_body("worm")
    with SoftBodyBackend(body) as backend:
        backend.send_command(JointCommand(np.tile([0.0, 0.0, 0.3], body.lattice.segments)))
        backend.advance(0.01)
        state = backend.read_state()
        axial_effort = state.effort_nm[2::3]
    # The muscles pull the segments shorter (positive effort along +strain) while they shorten
    # towards the command, so the muscles deliver power.
    assert np.all(state.velocity_rad_s[2::3] > 0)
    assert float(state.effort_nm @ state.velocity_rad_s) > 0
    assert np.all(axial_effort > 0)


def test_same_inputs_give_identical_runs() -> None:
    body = load_body("snake")

    def trace() -> np.ndarray:
        rows = []
        with SoftBodyBackend(body) as backend:
            for k in range(60):
                yaw = 0.4 * np.sin(0.06 * k - np.arange(body.lattice.segments))
                command = np.zeros(body.joint_count)
                command[0::3] = yaw
                backend.send_command(JointCommand(command))
                backend.advance(0.01)
                rows.append(backend.positions().copy())
        return np.array(rows)

    np.testing.assert_array_equal(trace(), trace())


def test_an_unstable_body_raises_instead_of_returning_garbage() -> None:
    body = load_body("worm")
    # Springs far too stiff for the step: bypasses the loader's check on purpose.
    body = replace(body, springs=replace(body.springs, k=400.0, damping=0.0))
    with SoftBodyBackend(body) as backend:
        backend.send_command(JointCommand(np.tile([0.5, 0.5, 0.4], body.lattice.segments)))
        with pytest.raises(SimulationDivergedError, match="diverged"):
            for _ in range(200):
                backend.advance(0.01)


def test_control_period_must_be_whole_steps() -> None:
    with SoftBodyBackend(load_body("worm")) as backend, pytest.raises(ConfigError, match="whole"):
        backend.advance(0.0105)


def test_spec_exports_and_reloads_with_its_skin() -> None:
    xml = build_body_spec(load_body("worm")).to_xml()
    model = mujoco.MjModel.from_xml_string(xml)
    assert model.nskin == 1 and model.nu == 114 and model.ntendon == 114


def test_mujoco_draws_the_skin_on_the_b_spline_surface_of_the_moving_lattice() -> None:
    from snakebot.backends.softbody.skin import skin_mesh

    body = load_body("snake")
    with SoftBodyBackend(body) as backend:
        backend.send_command(JointCommand(np.tile([0.4, 0.2, 0.2], body.lattice.segments)))
        for _ in range(20):
            backend.advance(0.01)
        model, data = backend.model, backend.data
        mujoco.mj_forward(model, data)  # body poses of the current state
        scene = mujoco.MjvScene(model, maxgeom=100)
        mujoco.mjv_updateScene(
            model,
            data,
            mujoco.MjvOption(),
            None,
            mujoco.MjvCamera(),
            mujoco.mjtCatBit.mjCAT_ALL,
            scene,
        )
        drawn = np.array(scene.skinvert).reshape(-1, 3)
        positions = backend.positions()
    mesh = skin_mesh(backend.lattice.rings, backend.start_positions)
    normals = np.array(scene.skinnormal).reshape(-1, 3)
    inflate = body.lattice.point_radius_m
    np.testing.assert_allclose(drawn - inflate * normals, mesh.weights @ positions, atol=1e-6)
