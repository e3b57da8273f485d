"""The backend contract as a pytest suite: subclass :class:`BackendContract` to run it.

::

    # test_my_backend.py
    from snakebot.testing import BackendContract

    class TestMyBackend(BackendContract):
        def make(self, robot):              # a RobotConfig -> a new, unconnected Backend
            return MyBackend(robot)

Every ``test_*`` method then runs on your backend: lifecycle errors (before connect, twice,
after close), torque at close as the stop policy says, time passing by ``dt``, state shapes,
refused command shapes, a commanded step converging, torque off/gains/torque on. For a backend
that needs a resource per test (a port, an emulator), override :meth:`backends` instead: a
context manager yielding the factory. ``tolerance_rad`` and ``settle_s`` loosen the tracking
checks for a slow servo loop.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

import numpy as np
import pytest

from snakebot.backends.base import Backend
from snakebot.config import RobotConfig, load_robot
from snakebot.errors import BackendStateError
from snakebot.types import JointCommand, PDGains

RobotFactory = Callable[[RobotConfig], Backend]
"""A robot config -> a new, unconnected backend for it."""


class BackendContract:
    """The conformance suite; a subclass named ``Test...`` defines :meth:`make` (or
    :meth:`backends`) and pytest runs every check on its backend.

    The checks use the shipped robots ``snake8`` (8 joints) and ``snake12`` (12 joints).
    """

    tolerance_rad: float = 0.03
    """How close a commanded pose must be reached, in rad."""
    settle_s: float = 1.5
    """How long a commanded step may take to settle, in s."""

    def make(self, robot: RobotConfig) -> Backend:
        """A new, unconnected backend for ``robot``; override this (or :meth:`backends`)."""
        raise NotImplementedError(
            f"{type(self).__name__}: define make(robot) -> Backend, or backends()"
        )

    @contextlib.contextmanager
    def backends(self) -> Iterator[RobotFactory]:
        """A context manager yielding the factory, around each test (default: :meth:`make`)."""
        yield self.make

    @pytest.fixture
    def make_backend(self) -> Iterator[Callable[[str], Backend]]:
        """A factory of backends by robot name, valid for one test."""
        with self.backends() as factory:
            yield lambda name: factory(load_robot(name))

    # -- lifecycle ---------------------------------------------------------------------------
    def test_calls_before_connect_fail_clearly(
        self, make_backend: Callable[[str], Backend]
    ) -> None:
        """Reading, commanding or advancing before connect is a BackendStateError."""
        backend = make_backend("snake8")
        with pytest.raises(BackendStateError, match="not connected"):
            backend.read_state()
        with pytest.raises(BackendStateError, match="call connect"):
            backend.send_command(JointCommand(np.zeros(8)))
        with pytest.raises(BackendStateError):
            backend.advance(0.01)

    def test_connect_twice_fails_clearly(self, make_backend: Callable[[str], Backend]) -> None:
        """A second connect is a BackendStateError saying so."""
        with make_backend("snake8") as backend, pytest.raises(BackendStateError, match="already"):
            backend.connect()

    def test_close_is_idempotent_and_final(self, make_backend: Callable[[str], Backend]) -> None:
        """close twice is fine; after it every call (connect too) is refused."""
        backend = make_backend("snake8")
        backend.connect()
        backend.close()
        backend.close()
        with pytest.raises(BackendStateError, match="closed"):
            backend.read_state()
        with pytest.raises(BackendStateError, match="closed"):
            backend.connect()

    def test_close_leaves_torque_as_configured(
        self, make_backend: Callable[[str], Backend]
    ) -> None:
        """Torque on while connected; after close, on for 'hold', off for 'limp'."""
        backend = make_backend("snake8")
        with backend:
            assert backend.torque_enabled
        assert backend.torque_enabled == (backend.stop_policy == "hold")

    # -- the cycle ---------------------------------------------------------------------------
    def test_advance_moves_time_by_dt(self, make_backend: Callable[[str], Backend]) -> None:
        """Ten advances of 0.02 s move robot time by 0.2 s."""
        with make_backend("snake8") as backend:
            start = backend.read_state().time_s
            for _ in range(10):
                backend.advance(0.02)
            elapsed = backend.read_state().time_s - start
        assert elapsed == pytest.approx(0.2, abs=0.03)

    def test_state_has_one_value_per_joint(self, make_backend: Callable[[str], Backend]) -> None:
        """Positions, velocities and efforts are finite, shape (N,)."""
        with make_backend("snake12") as backend:
            state = backend.read_state()
        for array in (state.position_rad, state.velocity_rad_s, state.effort_nm):
            assert array.shape == (12,)
            assert np.isfinite(array).all()

    def test_wrong_command_shape_is_refused(self, make_backend: Callable[[str], Backend]) -> None:
        """A command of the wrong length is a ValueError naming the shape."""
        with (
            make_backend("snake8") as backend,
            pytest.raises(ValueError, match=r"expected \(8,\)"),
        ):
            backend.send_command(JointCommand(np.zeros(7)))

    def test_commanded_step_converges(self, make_backend: Callable[[str], Backend]) -> None:
        """A step to a pose is reached within tolerance_rad after settle_s."""
        goal = np.array([0.3, -0.3, 0.2, -0.2, 0.1, -0.1, 0.25, -0.25])
        with make_backend("snake8") as backend:
            backend.send_command(JointCommand(goal))
            for _ in range(round(self.settle_s / 0.01)):
                backend.advance(0.01)
            state = backend.read_state()
        np.testing.assert_allclose(state.position_rad, goal, atol=self.tolerance_rad)

    def test_torque_off_then_gains_on_again(self, make_backend: Callable[[str], Backend]) -> None:
        """Torque off, new gains, torque on: the joints track again."""
        with make_backend("snake8") as backend:
            backend.set_torque(False)
            assert not backend.torque_enabled
            backend.set_gains(PDGains(kp_nm_per_rad=3.0, kd_nms_per_rad=0.0))  # XL430 P = 800
            backend.set_torque(True)
            backend.send_command(JointCommand(np.full(8, 0.2)))
            for _ in range(round(self.settle_s / 0.01)):
                backend.advance(0.01)
            position = backend.read_state().position_rad
        assert np.all(np.abs(position - 0.2) < self.tolerance_rad)
