"""A mass-spring body as a Backend: the controller's joints are its muscle channels.

Joint ``j`` is channel ``muscles.channels[j % k]`` of segment ``j // k``: yaw and pitch in rad,
axial in strain. ``send_command`` sets the muscles' rest lengths (snakebot.backends.softbody.
muscles); ``advance`` steps MuJoCo and applies Miller's directional friction after every step;
``read_state`` measures the channels from the lattice's shape, so tracking errors compare like
with like. Efforts are generalised muscle forces (N·m for bends, N·m per unit strain), so effort
times velocity is the muscles' power; its positive part is integrated over every physics step
(``MuscleMap.power_rows``) into ``JointState.positive_work_j``.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Literal

import mujoco
import numpy as np

from snakebot.backends.base import Backend
from snakebot.backends.pacing import Pacer
from snakebot.backends.softbody import friction_c
from snakebot.backends.softbody.friction import DirectionalFriction, contact_normal_forces
from snakebot.backends.softbody.health import (
    DEFAULT_BODY_LIMITS,
    BodyHealthLimits,
    BodyHealthMonitor,
)
from snakebot.backends.softbody.model import build_body_model
from snakebot.backends.softbody.muscles import ChannelLayout, MuscleMap
from snakebot.backends.twin.readouts import StepCheck
from snakebot.backends.twin.terrain.cliff import Cliff
from snakebot.config.body import BodyConfig
from snakebot.errors import ConfigError
from snakebot.types import BodyState, JointState, PDGains


@dataclass(frozen=True)
class _Snapshot:
    """What one state of the lattice measures: channels and their rates (3, S) each, ring
    centres (R, 3) and the head ring's frame (3, 3), columns forward, left, up."""

    channels: np.ndarray
    rates: np.ndarray
    centres: np.ndarray
    head_frame: np.ndarray


class SoftBodyBackend(Backend):
    """Steps Miller's lattice of ``body``; as fast as possible, or paced to the wall clock.

    Options: ``friction`` (floor coefficient, overrides ``ground.friction``), ``directional``
    (Miller's rule on or off, overrides ``ground.directional``), ``terrain`` (a Cliff, or None
    for the flat floor), ``realtime`` and ``implementation``: "c" steps the physics and the rule
    in compiled C (friction_c; numpy with a warning where nothing compiles), "numpy" keeps the
    Python loop with the numpy rule (the reference; both agree bit for bit). Control periods
    must be whole numbers of timesteps. ``health`` sets the physics checks (point penetration,
    airborne time, spring strain, energy: softbody.health; None: no checks), reported by
    ``physics_health`` (ChecksPhysics); a hard limit raises PhysicsHealthError.
    ``backward_ratio`` makes Miller's ideal scales finite: backward friction that many times the
    floor's (>= 1; inf, the default, is Miller's no-backward rule; friction.py).

    A mass-spring muscle has no position loop: its stiffness and damping are the body file's
    springs, so ``set_gains`` records the gains and changes nothing. Torque off relaxes every
    muscle to the rest shape (``stop_policy = "limp"``).
    """

    def __init__(
        self,
        body: BodyConfig,
        *,
        friction: float | None = None,
        directional: bool | None = None,
        terrain: Cliff | None = None,
        realtime: bool = False,
        implementation: Literal["c", "numpy"] = "c",
        health: BodyHealthLimits | None = DEFAULT_BODY_LIMITS,
        backward_ratio: float = math.inf,
    ) -> None:
        super().__init__()
        if not backward_ratio >= 1.0:
            raise ConfigError(
                "backward_ratio", "", f"expected a number >= 1 (or inf), got {backward_ratio}"
            )
        self.backward_ratio = backward_ratio
        self._health_limits = health
        self.physics_monitor: BodyHealthMonitor | None = None
        self.robot = body  # the config under the name the other backends use
        self.body = body
        self.joint_count = body.joint_count
        self.stop_policy = body.safety.stop_policy
        self.directional = body.ground.directional if directional is None else directional
        self.friction = body.ground.friction if friction is None else friction
        self.terrain = terrain
        self.gains: PDGains | None = None
        self._realtime = realtime
        self.implementation = implementation
        self._pacer: Pacer | None = None
        self._layout = ChannelLayout(body.muscles.channels, body.lattice.segments)
        self._command = np.zeros(self.joint_count)
        self._work_j = np.zeros(self.joint_count)  # positive muscle work per joint since connect
        self._spring_work_j = 0.0  # every spring's positive work since connect (health budget)
        self.model: mujoco.MjModel
        self.data: mujoco.MjData

    # -- lifecycle ---------------------------------------------------------------------------
    def _connect(self) -> None:
        if not (math.isfinite(self.friction) and self.friction >= 0):
            raise ConfigError("friction", "", f"expected a number >= 0, got {self.friction}")
        built = build_body_model(self.body, friction=self.friction, terrain=self.terrain)
        self.model, self.lattice = built.model, built.lattice
        self.data = mujoco.MjData(self.model)
        self._step_check = StepCheck(self.model, self.data, finite_positions=True)
        self.start_positions = built.start_positions
        lat = self.body.lattice
        self.muscles = MuscleMap(self.lattice, lat.segment_length_m, lat.width_m, lat.height_m)
        self.friction_rule = DirectionalFriction(
            built.point_geoms, self.model.ngeom, built.start_positions
        )
        self._point_geoms = built.point_geoms
        self.friction_rule.enabled = self.directional
        self.friction_rule.set_backward(
            self.backward_ratio,
            self.friction,
            float(self.model.opt.timestep),
            self.body.lattice.point_mass_kg,
        )
        self._stepper: friction_c.CompiledStepper | None = None
        if self.implementation == "c":
            try:
                self._stepper = friction_c.CompiledStepper(
                    self.model, self.data, self.friction_rule
                )
            except friction_c.CompileError as exc:
                warnings.warn(
                    f"the soft body steps in Python, about half as fast as C: {exc}",
                    RuntimeWarning,
                    stacklevel=2,
                )
                self.implementation = "numpy"
        # Views into MjData: point displacements and world velocities, (P, 3) each.
        self._displacement = self.data.qpos.reshape(-1, 3)
        self._velocity = self.data.qvel.reshape(-1, 3)
        self._previous = self.start_positions.copy()
        self._previous_time = 0.0
        self._snapshot: _Snapshot | None = None
        self.torque_enabled = True
        self._apply_muscles()
        mujoco.mj_forward(self.model, self.data)
        self._start_com = self._measure().centres.mean(axis=0)
        self._axis_sum = np.zeros(3)
        self._contact_sum = 0.0
        self._cycles = 0
        self._steps: dict[float, int] = {}
        self._pacer = Pacer(self.stats) if self._realtime else None
        self._point_bodies = np.array(
            [self.model.geom_bodyid[g] for g in built.point_geoms], dtype=np.intp
        )
        self.reset_physics_health()

    def reset_physics_health(self) -> None:
        """Start the physics-health account afresh (ChecksPhysics): the checks and the muscles'
        work count from here; they stay off where they are off."""
        self._work_at_reset = float(self._work_j.sum())
        self._spring_work_at_reset = self._spring_work_j
        if self._health_limits is None:
            return
        self.physics_monitor = BodyHealthMonitor(
            self.model,
            self.data,
            self._point_geoms,
            self._point_bodies,
            self.body.lattice.point_radius_m,
            self._health_limits,
        )

    def physics_health(self) -> dict[str, object] | None:
        """The run's physics health so far (docs/soft-bodies.md, "Physics health"); None with
        the checks off."""
        if self.physics_monitor is None:
            return None
        return self.physics_monitor.summary(
            float(self._work_j.sum()) - self._work_at_reset,
            self._spring_work_j - self._spring_work_at_reset,
        )

    def _close(self) -> None:
        self.stats.extra.update(self.travel())
        self.set_torque(self.stop_policy == "hold")

    # -- geometry ------------------------------------------------------------------------------
    def positions(self) -> np.ndarray:
        """World positions (P, 3) of the point masses in lattice order, now."""
        return self.start_positions + self._displacement  # type: ignore[no-any-return]

    def _channels(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if not self.torque_enabled:
            zero = np.zeros(self.body.lattice.segments)
            return zero, zero, zero
        return self._layout.split(self._command)

    def _ring_scale(self) -> np.ndarray:
        if not self.body.muscles.volume_preservation:
            return np.ones(self.lattice.rings)
        return self.muscles.ring_scale(self.muscles.segment_lengths(self.positions()))

    def _apply_muscles(self) -> None:
        """Write every spring's rest length for the command (or the rest shape, torque off), and
        keep d(rest length)/d(channel) for the efforts."""
        yaw, pitch, axial = self._channels()
        rest, self._jacobian = self.muscles.rest_lengths_and_jacobian(
            yaw, pitch, axial, self._ring_scale()
        )
        self.data.ctrl[:] = rest
        self._power_rows: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # when stepping

    # -- the cycle ---------------------------------------------------------------------------
    def _measure(self) -> _Snapshot:
        """Measure the lattice now and one physics step earlier (for rates), once per state."""
        if self._snapshot is None:
            both = np.stack((self._previous, self.positions()))
            centres, forward, left, up = self.muscles.ring_axes(both)
            channels = np.stack(self.muscles.channels_of(centres, forward, left, up), axis=1)
            elapsed = float(self.data.time) - self._previous_time
            rates = (channels[1] - channels[0]) / elapsed if elapsed > 0 else 0.0 * channels[1]
            head = np.stack((forward[1, 0], left[1, 0], up[1, 0]), axis=1)
            self._snapshot = _Snapshot(channels[1], rates, centres[1], head)
        return self._snapshot

    def _read_state(self) -> JointState:
        snapshot = self._measure()
        effort = self.muscles.segment_efforts(self._jacobian, self.data.actuator_force)
        return JointState(
            time_s=float(self.data.time),
            position_rad=self._layout.join(*snapshot.channels),
            velocity_rad_s=self._layout.join(*snapshot.rates),
            effort_nm=self._layout.join(*effort),
            positive_work_j=self._work_j,  # never written in place: each period makes a new one
        )

    def _send_command(self, position_rad: np.ndarray) -> None:
        self._command = position_rad.copy()
        self._apply_muscles()

    def _set_gains(self, gains: PDGains) -> None:
        self.gains = gains

    def _set_torque(self, enabled: bool) -> None:
        self.torque_enabled = enabled
        self._apply_muscles()

    def steps_for(self, dt_s: float) -> int:
        """Physics steps in a control period; it must be a whole number of timesteps."""
        timestep = float(self.model.opt.timestep)
        steps = round(dt_s / timestep)
        if steps < 1 or not math.isclose(steps * timestep, dt_s, rel_tol=1e-6):
            raise ConfigError(
                "rate_hz",
                "",
                f"control period {dt_s:g} s is not a whole number of {timestep:g} s physics "
                f"steps; pick a rate that divides {1 / timestep:g} Hz (e.g. 50, 100, 250)",
            )
        self._steps[dt_s] = steps
        return steps

    def _advance(self, dt_s: float) -> None:
        steps = self._steps.get(dt_s) or self.steps_for(dt_s)
        model, data = self.model, self.data
        if self.body.muscles.volume_preservation:
            self._apply_muscles()
        self._step_check.start()
        rule, displacement, velocity = self.friction_rule, self._displacement, self._velocity
        self._snapshot = None
        if self._power_rows is None:
            self._power_rows = self.muscles.power_rows(self._jacobian, self._layout)
        columns, effort_rows, rate_rows = self._power_rows
        timestep = float(model.opt.timestep)
        if self._stepper is not None:
            work, spring = self._stepper.advance(steps, columns, effort_rows, rate_rows)
            self._spring_work_j += spring
            self._previous = self.start_positions + self._stepper.previous
            self._previous_time = self._stepper.previous_time_s
            self._work_j = self._work_j + work
            self._finish_advance(steps, dt_s)
            return
        forces = np.empty((steps, model.nu))
        rates = np.empty((steps, model.nu))
        for step in range(steps):
            if step == steps - 1:
                self._previous = self.positions()
                self._previous_time = float(data.time)
            mujoco.mj_step(model, data)
            # The step's forces and spring rates, computed at its start (before the rule).
            forces[step] = data.actuator_force
            rates[step] = data.actuator_velocity
            if rule.enabled and data.ncon:
                normal = None if rule.ideal else contact_normal_forces(data)
                rule.apply(displacement, velocity, data.contact.geom, normal)
        self._work_j = self._work_j + muscle_work_j(
            forces, rates, columns, effort_rows, rate_rows, timestep
        )
        self._spring_work_j += spring_work_j(forces, rates, timestep)
        self._finish_advance(steps, dt_s)

    def _finish_advance(self, steps: int, dt_s: float) -> None:
        self._step_check.finish(steps)
        if self.physics_monitor is not None:
            self.physics_monitor.sample(self.data, self._spring_work_j - self._spring_work_at_reset)
        self._track()
        if self._pacer is not None:
            self._pacer.wait(dt_s)

    # -- whole-body measures ------------------------------------------------------------------
    def body_state(self) -> BodyState:
        """Centre of mass of the points and the head ring's orientation (w, x, y, z)."""
        self._require_connected()
        snapshot = self._measure()
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, snapshot.head_frame.reshape(-1))
        return BodyState(com_m=snapshot.centres.mean(axis=0), head_quat=quat)

    def _track(self) -> None:
        """Accumulate the body axis and floor contact once per control cycle."""
        centres = self._measure().centres
        axis = centres[0] - centres[-1]
        self._axis_sum += axis / max(math.sqrt(float(axis @ axis)), 1e-12)
        if self.data.ncon:
            touching = self.friction_rule.touching(self.data.contact.geom)
            self._contact_sum += float(np.count_nonzero(touching)) / self.lattice.points
        self._cycles += 1

    def travel(self) -> dict[str, float]:
        """Since connect: the mean body axis (tail to head) and the angle from it to the net
        COM displacement, both in degrees in the horizontal plane (0: head first, ±90: sideways,
        ±180: tail first), and the mean fraction of points touching the ground."""
        dx, dy = (self._measure().centres.mean(axis=0) - self._start_com)[:2]
        axis = math.degrees(math.atan2(self._axis_sum[1], self._axis_sum[0]))
        heading = math.degrees(math.atan2(dy, dx))
        return {
            "body_axis_deg": axis,
            "travel_angle_deg": math.remainder(heading - axis, 360.0),
            "contact_fraction": self._contact_sum / max(self._cycles, 1),
        }


def muscle_work_j(
    force_n: np.ndarray,
    rate_m_s: np.ndarray,
    columns: np.ndarray,
    effort_rows: np.ndarray,
    rate_rows: np.ndarray,
    timestep_s: float,
) -> np.ndarray:
    """Each joint's positive muscle work (N,) J over S physics steps: the springs' forces and
    rates of length (S, M) at the start of each step, turned into joint efforts and channel
    rates by ``MuscleMap.power_rows`` (its springs ``columns`` and weights, (N, K) each); a
    step counts max(effort · rate, 0) · h."""
    effort = (force_n[:, columns] * effort_rows).sum(axis=-1)  # (S, N)
    rate = (rate_m_s[:, columns] * rate_rows).sum(axis=-1)
    power = effort * rate
    work: np.ndarray = np.where(power > 0.0, power, 0.0).sum(axis=0) * timestep_s
    return work


def spring_work_j(force_n: np.ndarray, rate_m_s: np.ndarray, timestep_s: float) -> float:
    """All springs' positive work over S physics steps, J: Σ max(f·dl/dt, 0)·h over the steps
    and springs, from their forces and rates of length (S, M) at each step's start. Every joule
    of motion the springs give the points passes through it (the physics check's budget)."""
    power = force_n * rate_m_s
    return float(np.where(power > 0.0, power, 0.0).sum()) * timestep_s
