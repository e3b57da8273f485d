"""The backend contract as a pytest suite: subclass :class:`BackendContract` to run it.

::

    # test_my_backend.py
    from snakebot.testing import BackendContract

    class TestMyBackend(BackendContract):
        def make(self, robot):              # a RobotConfig -> a new, unconnected Backend
            return MyBackend(robot)

Every ``test_*`` method then runs on your backend: lifecycle errors (before connect, twice,
after close), torque at close as the stop policy says, time passing by ``dt``, state shapes,
refused command shapes, a commanded step converging, torque off/gains/torque on. Then each
optional ability the backend has (``snakebot.backends.capabilities``: body state, IMU, health
readings, physics checks, current sensing, reset, a MuJoCo model, a bus) is held to what it
promises; the checks of an ability the backend does not have are skipped, saying so. For a
backend that needs a resource per test (a port, an emulator), override :meth:`backends`
instead: a context manager yielding the factory. ``tolerance_rad`` and ``settle_s`` loosen the
tracking checks for a slow servo loop; ``time_tolerance_s`` is how late robot time may run.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

import numpy as np
import pytest

from snakebot.backends.base import Backend
from snakebot.backends.capabilities import (
    ChecksPhysics,
    LimitsTorque,
    OnBus,
    ReportsHealth,
    ReportsTravel,
    Resettable,
    SensesBody,
    SensesCurrent,
    SensesImu,
    SensesTorque,
    Simulated,
)
from snakebot.config import RobotConfig, load_robot
from snakebot.control.metrics import head_yaw_rad
from snakebot.errors import BackendStateError
from snakebot.types import JointCommand, JointState, PDGains

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
    time_tolerance_s: float = 0.005
    """How much later than ``n * dt`` robot time may be after ``n`` advances of ``dt``; never
    earlier. A simulation's time is exact (set 1e-9); a backend on the wall clock sleeps to
    deadlines, so its time is late by its last sleep's overshoot plus one state read: under
    2 ms for the emulated Dynamixel chain on a 2-core machine at load 3 (median 0.9 ms), so
    5 ms leaves room without letting a backend lose or gain a cycle (20 ms at 50 Hz)."""
    health_cycles: int = 40
    """Cycles after which a backend that reports health has a first slow reading."""

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
        assert elapsed >= 0.2 - 1e-9, f"robot time ran short: {elapsed!r} s for 0.2 s"
        assert elapsed <= 0.2 + self.time_tolerance_s, (
            f"robot time ran late: {elapsed!r} s for 0.2 s (tolerance {self.time_tolerance_s} s)"
        )

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

    # -- optional abilities: each claimed one keeps its promise ---------------------------------
    def _bend(self, backend: Backend, goal: np.ndarray, seconds: float, dt: float = 0.01) -> None:
        backend.send_command(JointCommand(goal))
        for _ in range(round(seconds / dt)):
            backend.advance(dt)

    def test_body_state_places_the_body_in_the_world(
        self, make_backend: Callable[[str], Backend]
    ) -> None:
        """SensesBody: a finite COM (3,) above the ground and a unit head quaternion; bending
        the joints turns the head. Refused before connect."""
        backend = make_backend("snake8")
        if not isinstance(backend, SensesBody):
            pytest.skip(_not_claimed(backend, SensesBody))
        with pytest.raises(BackendStateError):
            backend.body_state()
        with backend:
            start = backend.body_state()
            self._bend(backend, np.full(8, 0.3), 0.5)
            bent = backend.body_state()
        for body in (start, bent):
            assert body.com_m.shape == (3,) and np.isfinite(body.com_m).all()
            assert body.com_m[2] > 0, f"the centre of mass is below the ground: {body.com_m}"
            assert body.head_quat.shape == (4,)
            assert np.linalg.norm(body.head_quat) == pytest.approx(1.0, abs=1e-6)
        turned = abs(head_yaw_rad(bent.head_quat) - head_yaw_rad(start.head_quat))
        assert turned > 0.05, f"the joints bent 0.3 rad each and the head turned {turned} rad"

    def test_imu_gyro_integrates_to_the_head_turn(
        self, make_backend: Callable[[str], Backend]
    ) -> None:
        """SensesImu: the head gyro's yaw rate, integrated while the joints bend, is the turn of
        the head's quaternion (within 10 %); at rest it reads about zero."""
        backend = make_backend("snake8")
        if not isinstance(backend, SensesImu):
            pytest.skip(_not_claimed(backend, SensesImu))
        dt = 0.002
        with backend:
            before = backend.body_state()
            assert before.head_gyro_rad_s is not None
            assert np.abs(backend.head_gyro_rad_s()).max() < 0.05, "the gyro moves at rest"
            backend.send_command(JointCommand(np.full(8, 0.3)))
            rates = [backend.head_gyro_rad_s()[2]]
            for _ in range(round(0.4 / dt)):
                backend.advance(dt)
                rates.append(backend.head_gyro_rad_s()[2])
            after = backend.body_state()
        gyro_turn = float(np.trapezoid(rates, dx=dt))
        turn = head_yaw_rad(after.head_quat) - head_yaw_rad(before.head_quat)
        assert abs(turn) > 0.05, f"the head turned only {turn} rad"
        assert gyro_turn == pytest.approx(turn, rel=0.1), "the gyro and the pose disagree"

    def test_health_readings_are_per_joint(self, make_backend: Callable[[str], Backend]) -> None:
        """ReportsHealth: after ``health_cycles`` cycles there are readings, each a finite
        (N,) array under a name that ends in its unit (``temperature_c``)."""
        backend = make_backend("snake8")
        if not isinstance(backend, ReportsHealth):
            pytest.skip(_not_claimed(backend, ReportsHealth))
        with backend:
            for _ in range(self.health_cycles):
                backend.read_state()
                backend.advance(0.01)
            readings = dict(backend.health())
        assert readings, f"no health readings after {self.health_cycles} cycles"
        for name, values in readings.items():
            assert "_" in name, f"{name!r} does not say its unit"
            assert np.shape(values) == (8,) and np.isfinite(values).all(), name

    def test_physics_health_starts_afresh(self, make_backend: Callable[[str], Backend]) -> None:
        """ChecksPhysics: a run's account grows with what happened (the joint speed it saw);
        after reset_physics_health it is the account of a run that has not moved."""
        backend = make_backend("snake8")
        if not isinstance(backend, ChecksPhysics):
            pytest.skip(_not_claimed(backend, ChecksPhysics))
        with backend:
            fresh = backend.physics_health()
            if fresh is None:
                pytest.skip("physics checks are switched off on this backend")
            self._bend(backend, np.full(8, 0.3), 0.3)
            moved = backend.physics_health()
            backend.reset_physics_health()
            again = backend.physics_health()
        assert moved is not None and again is not None
        assert moved != fresh, "the account did not change while the joints moved"
        assert again == fresh

    def test_current_follows_the_effort(self, make_backend: Callable[[str], Backend]) -> None:
        """SensesCurrent: a finite (N,) current in A; more while the joints drive a step than
        when they have settled still."""
        backend = make_backend("snake8")
        if not isinstance(backend, SensesCurrent):
            pytest.skip(_not_claimed(backend, SensesCurrent))
        with backend:
            backend.send_command(JointCommand(np.full(8, 0.4)))
            backend.advance(0.01)
            backend.read_state()
            driving = np.abs(backend.present_current_a())
            self._bend(backend, np.full(8, 0.4), self.settle_s)
            backend.read_state()
            settled = np.abs(backend.present_current_a())
        assert driving.shape == (8,) and np.isfinite(driving).all()
        assert driving.sum() > 2 * settled.sum() and driving.sum() > 0.01, (driving, settled)

    def test_torque_is_the_states_effort_and_follows_the_drive(
        self, make_backend: Callable[[str], Backend]
    ) -> None:
        """SensesTorque: a finite (N,) torque in N*m, the last state's effort; more while the
        joints drive a step than once they have settled still."""
        backend = make_backend("snake8")
        if not isinstance(backend, SensesTorque):
            pytest.skip(_not_claimed(backend, SensesTorque))
        with backend:
            backend.send_command(JointCommand(np.full(8, 0.4)))
            backend.advance(0.01)
            state = backend.read_state()
            driving = backend.measured_torque_nm()
            self._bend(backend, np.full(8, 0.4), self.settle_s)
            backend.read_state()
            settled = backend.measured_torque_nm()
        assert driving.shape == (8,) and np.isfinite(driving).all()
        np.testing.assert_array_equal(driving, state.effort_nm)
        assert np.abs(driving).sum() > 2 * np.abs(settled).sum(), (driving, settled)
        assert np.abs(driving).sum() > 0.01, driving

    def test_torque_limit_caps_the_push_and_the_joints_still_follow(
        self, make_backend: Callable[[str], Backend]
    ) -> None:
        """LimitsTorque: capped (before connect) at a quarter of what the servos push to drive
        a step, they push with no more than the cap and still move towards the goal; a bad
        cap is a ValueError. Needs SensesTorque to see the push."""
        free, capped = make_backend("snake8"), make_backend("snake8")
        if not isinstance(capped, LimitsTorque):
            pytest.skip(_not_claimed(capped, LimitsTorque))
        if not isinstance(capped, SensesTorque):
            pytest.skip(f"{type(capped).__name__} claims LimitsTorque but cannot show the push")
        for bad in (0.0, -1.0, float("nan"), np.ones(3)):
            with pytest.raises(ValueError):
                capped.limit_torque(bad)
        step = np.full(8, 0.4)

        def drive(backend: Backend) -> tuple[float, np.ndarray]:
            peak = 0.0
            backend.send_command(JointCommand(step))
            for _ in range(round(self.settle_s / 0.01)):
                backend.advance(0.01)
                peak = max(peak, float(np.abs(backend.read_state().effort_nm).max()))
            return peak, backend.read_state().position_rad

        with free:
            full_push, _ = drive(free)
        cap = full_push / 4
        capped.limit_torque(np.full(8, cap))
        with capped:
            push, position = drive(capped)
        assert full_push > 0.01, full_push
        assert push <= 1.15 * cap, (push, cap, full_push)
        assert float(np.mean(position)) > 0.1, position  # it still follows the goal

    def test_travel_figures_are_finite_and_named(
        self, make_backend: Callable[[str], Backend]
    ) -> None:
        """ReportsTravel: after the joints moved, named finite figures."""
        backend = make_backend("snake8")
        if not isinstance(backend, ReportsTravel):
            pytest.skip(_not_claimed(backend, ReportsTravel))
        with backend:
            self._bend(backend, np.full(8, 0.3), 0.3)
            figures = dict(backend.travel())
        assert figures, "no travel figures after the joints moved"
        for name, value in figures.items():
            assert "_" in name and np.isfinite(value), (name, value)

    def test_reset_is_as_good_as_a_new_backend(
        self, make_backend: Callable[[str], Backend]
    ) -> None:
        """Resettable: after moving, reset gives time 0, the joints straight and still, the body
        where a new backend starts it; the same commands then give the same states as on a new
        backend. ``reset(pose)`` starts in that pose."""
        first = make_backend("snake8")
        if not isinstance(first, Resettable):
            pytest.skip(_not_claimed(first, Resettable))
        goals = [np.full(8, 0.3), np.linspace(-0.3, 0.3, 8)]
        with first, make_backend("snake8") as new:
            assert isinstance(new, Resettable)
            self._bend(first, goals[0], 0.3)
            state = first.reset()
            assert state.time_s == 0.0
            np.testing.assert_allclose(state.position_rad, 0.0, atol=1e-9)
            np.testing.assert_allclose(state.velocity_rad_s, 0.0, atol=1e-9)
            if isinstance(first, SensesBody) and isinstance(new, SensesBody):
                np.testing.assert_allclose(first.body_state().com_m, new.body_state().com_m)
            replay = [_replay(first, goals), _replay(new, goals)]
            np.testing.assert_allclose(replay[0], replay[1], atol=1e-9)
            pose = np.linspace(-0.2, 0.2, 8)
            state = first.reset(pose)
            np.testing.assert_allclose(state.position_rad, pose, atol=1e-9)
            self._bend(first, pose, 0.2)
            np.testing.assert_allclose(first.read_state().position_rad, pose, atol=0.02)
            with pytest.raises(ValueError, match=r"\(8,\)"):
                first.reset(np.zeros(7))

    def test_simulation_is_the_state_read(self, make_backend: Callable[[str], Backend]) -> None:
        """Simulated: a MuJoCo model and data, whose time is the time read_state reports."""
        import mujoco

        with make_backend("snake8") as backend:  # the model is built at connect
            if not isinstance(backend, Simulated):
                pytest.skip(_not_claimed(backend, Simulated))
            backend.advance(0.02)
            assert isinstance(backend.model, mujoco.MjModel)
            assert isinstance(backend.data, mujoco.MjData)
            assert float(backend.data.time) == backend.read_state().time_s

    def test_bus_reports_its_port_and_counts(self, make_backend: Callable[[str], Backend]) -> None:
        """OnBus: the port is named; the bus counts retries and alerts (none on a clean bus)."""
        backend = make_backend("snake8")
        if not isinstance(backend, OnBus):
            pytest.skip(_not_claimed(backend, OnBus))
        with backend:
            for _ in range(5):
                backend.read_state()
                backend.advance(0.01)
            assert isinstance(backend.port, str) and backend.port
            bus = backend.bus
            assert sum(bus.retry_counts.values()) + bus.group_retries >= 0
            assert not bus.alerts, f"servos raised alerts on a clean bus: {bus.conditions}"


def _not_claimed(backend: Backend, ability: type) -> str:
    return f"{type(backend).__name__} does not claim {ability.__name__}"


def _replay(backend: Backend, goals: list[np.ndarray]) -> np.ndarray:
    """Positions and velocities (2, N) after each goal played for 0.1 s, stacked."""
    states: list[JointState] = []
    for goal in goals:
        backend.send_command(JointCommand(goal))
        for _ in range(10):
            backend.advance(0.01)
        states.append(backend.read_state())
    return np.array([(s.position_rad, s.velocity_rad_s) for s in states])
