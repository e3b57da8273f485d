"""The conformance suite every backend passes (DESIGN.md, "The backend contract")."""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.errors import BackendStateError
from snakebot.types import JointCommand, PDGains
from tests.contract.conftest import BackendFactory


def test_calls_before_connect_fail_clearly(make_backend: BackendFactory) -> None:
    backend = make_backend("snake8")
    with pytest.raises(BackendStateError, match="not connected"):
        backend.read_state()
    with pytest.raises(BackendStateError, match="call connect"):
        backend.send_command(JointCommand(np.zeros(8)))
    with pytest.raises(BackendStateError):
        backend.advance(0.01)


def test_connect_twice_fails_clearly(make_backend: BackendFactory) -> None:
    with make_backend("snake8") as backend, pytest.raises(BackendStateError, match="already"):
        backend.connect()


def test_close_is_idempotent_and_final(make_backend: BackendFactory) -> None:
    backend = make_backend("snake8")
    backend.connect()
    backend.close()
    backend.close()
    with pytest.raises(BackendStateError, match="closed"):
        backend.read_state()
    with pytest.raises(BackendStateError, match="closed"):
        backend.connect()


def test_close_leaves_torque_as_configured(make_backend: BackendFactory) -> None:
    backend = make_backend("snake8")
    with backend:
        assert backend.torque_enabled
    assert backend.torque_enabled == (backend.stop_policy == "hold")


def test_advance_moves_time_by_dt(make_backend: BackendFactory) -> None:
    with make_backend("snake8") as backend:
        start = backend.read_state().time_s
        for _ in range(10):
            backend.advance(0.02)
        elapsed = backend.read_state().time_s - start
    assert elapsed == pytest.approx(0.2, abs=0.03)


def test_state_has_one_value_per_joint(make_backend: BackendFactory) -> None:
    with make_backend("snake12") as backend:
        state = backend.read_state()
    for array in (state.position_rad, state.velocity_rad_s, state.effort_nm):
        assert array.shape == (12,)
        assert np.isfinite(array).all()


def test_wrong_command_shape_is_refused(make_backend: BackendFactory) -> None:
    with make_backend("snake8") as backend, pytest.raises(ValueError, match=r"expected \(8,\)"):
        backend.send_command(JointCommand(np.zeros(7)))


def test_commanded_step_converges(make_backend: BackendFactory) -> None:
    goal = np.array([0.3, -0.3, 0.2, -0.2, 0.1, -0.1, 0.25, -0.25])
    with make_backend("snake8") as backend:
        backend.send_command(JointCommand(goal))
        for _ in range(150):
            backend.advance(0.01)
        state = backend.read_state()
    np.testing.assert_allclose(state.position_rad, goal, atol=0.03)


def test_torque_off_then_gains_on_again(make_backend: BackendFactory) -> None:
    with make_backend("snake8") as backend:
        backend.set_torque(False)
        assert not backend.torque_enabled
        backend.set_gains(PDGains(kp_nm_per_rad=3.0, kd_nms_per_rad=0.0))  # XL430 P = 800
        backend.set_torque(True)
        backend.send_command(JointCommand(np.full(8, 0.2)))
        for _ in range(150):
            backend.advance(0.01)
        assert np.all(np.abs(backend.read_state().position_rad - 0.2) < 0.03)
