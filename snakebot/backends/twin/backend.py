"""The MuJoCo twin as a Backend: same commands and states as the servo chain, physics inside."""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import mujoco
import numpy as np
import numpy.typing as npt

from snakebot.backends.base import Backend
from snakebot.backends.capabilities import Simulated, torque_caps
from snakebot.backends.pacing import Pacer
from snakebot.backends.twin import period_c
from snakebot.backends.twin.friction.scale import FrictionModel
from snakebot.backends.twin.health import DEFAULT_LIMITS, HealthLimits, HealthMonitor
from snakebot.backends.twin.imu import TwinSensors
from snakebot.backends.twin.model_builder import (
    GroundFriction,
    build_model,
    hold_ctrl_history,
    joint_name,
    link_name,
)
from snakebot.backends.twin.period_c import CompileError, PeriodStepper
from snakebot.backends.twin.readouts import (
    Capsules,
    StepCheck,
    as_slice,
    diverged_error,
    servo_torque_nm,
    step_work_j,
)
from snakebot.backends.twin.terrain import Terrain, as_terrain
from snakebot.config.schema import RobotConfig
from snakebot.errors import ConfigError, ServoFaultError
from snakebot.servo.dynamics import servo_dynamics
from snakebot.servo.electrical import ServoElectrics
from snakebot.types import BodyState, JointState, PDGains

JointSelection = int | slice | Sequence[int] | np.ndarray
"""Joints by numpy indexing: one index, a slice, indices, or a (N,) bool mask."""


__all__ = ["JointSelection", "Simulated", "TwinBackend"]


class TwinBackend(Backend):
    """Steps a MuJoCo model of ``robot``; as fast as possible, or paced to the wall clock.

    ``friction`` overrides the robot's ground model (``--friction``); ``timestep_s`` overrides
    ``twin.timestep_s``; ``terrain`` (a Terrain, ``--terrain`` text such as
    ``"pegs:density=12"``, or None for flat) sets the ground and the start pose;
    ``friction_model`` ("auto", "pairs", "scale"; None: the robot file's) how the ground's
    friction is made. A bad terrain raises ConfigError here, naming the key.
    Control periods passed to ``advance`` must be whole numbers of steps. ``health`` sets the
    physics checks (``twin.health.HealthLimits``; None: no checks), reported by
    ``physics_health``. The servo file's ``[twin]`` parts (docs/physics.md) add current draw,
    supply sag, overload protection (a trip raises ServoFaultError unless
    ``raise_on_overload`` is False, e.g. under the emulator, which latches it) and encoder and
    IMU noise drawn from ``seed``.

    Abilities (``backends.capabilities``): SensesBody, SensesImu, ChecksPhysics, SensesTorque,
    LimitsTorque, Resettable, Simulated; SensesCurrent where the servo file models the current
    (``stall_current_a``).
    """

    def __init__(
        self,
        robot: RobotConfig,
        *,
        friction: GroundFriction | None = None,
        timestep_s: float | None = None,
        realtime: bool = False,
        terrain: Terrain | str | None = None,
        friction_model: FrictionModel | None = None,
        health: HealthLimits | None = DEFAULT_LIMITS,
        seed: int = 0,
        raise_on_overload: bool = True,
    ) -> None:
        super().__init__()
        self._health_limits = health
        self.physics_monitor: HealthMonitor | None = None
        self.electrics: ServoElectrics | None = None
        self._seed = seed
        self.raise_on_overload = raise_on_overload
        self.robot = robot
        self.terrain = as_terrain(terrain)
        self._friction_model = friction_model
        self.joint_count = robot.joint_count
        self.stop_policy = robot.safety.stop_policy
        self._friction = friction
        self._timestep_override = timestep_s
        self._realtime = realtime
        self.model: mujoco.MjModel
        self.data: mujoco.MjData
        self._pacer: Pacer | None = None
        self._torque_now: np.ndarray | None = None  # servo torque (N,) at _torque_time_s
        self._torque_time_s = math.nan
        # The last period's readouts (period_c.Layout) at _period_time_s, for read_state and
        # body_state to hand over once each (no two states share one array).
        self._period_state: np.ndarray | None = None
        self._period_body: np.ndarray | None = None
        self._period_time_s = math.nan
        self._steps_per_period: dict[float, int] = {}
        self._work_j = np.zeros(self.joint_count)  # positive work per joint since connect/reset
        if robot.servo.physics.extras.stall_current_a is not None:
            self.present_current_a = self._present_current_a  # SensesCurrent: this servo file
        self._torque_cap_nm: np.ndarray | None = None  # LimitsTorque: per joint, N*m

    # -- lifecycle ---------------------------------------------------------------------------
    def _connect(self) -> None:
        self.model, _ = build_model(
            self.robot,
            friction=self._friction,
            timestep_s=self._timestep_override,
            terrain=self.terrain,
            friction_model=self._friction_model,
        )
        self.data = mujoco.MjData(self.model)
        self._step_check = StepCheck(self.model, self.data)
        joint_ids = [self.model.joint(joint_name(i)).id for i in range(self.joint_count)]
        self._qpos_index = np.array([self.model.jnt_qposadr[j] for j in joint_ids])
        self._dof_index = np.array([self.model.jnt_dofadr[j] for j in joint_ids])
        self._qpos_at, self._dof_at = as_slice(self._qpos_index), as_slice(self._dof_index)
        self._head_id = self.model.body(link_name(0)).id
        # Views into the model and data read every cycle, made once (MjData's buffers live as
        # long as it does; an attribute access builds a new array each time); a joint index
        # that is not a run of addresses stays a fancy index, a copy at every read.
        self._com_view = self.data.subtree_com[self._head_id]
        self._quat_view = self.data.xquat[self._head_id]
        self._views = isinstance(self._qpos_at, slice) and isinstance(self._dof_at, slice)
        if self._views:
            self._qpos_view = self.data.qpos[self._qpos_at]
            self._qvel_view = self.data.qvel[self._dof_at]
            self._damping_view = self.model.dof_damping[self._dof_at]
        self._force_view = self.data.actuator_force
        self._ctrl_view = self.data.ctrl
        # Each physics step's actuator forces and joint speeds of one control period, (S, N).
        self._step_force = np.zeros((0, self.joint_count))
        self._step_velocity = np.zeros((0, self.joint_count))
        self._period: PeriodStepper | None = None
        try:
            self._period = PeriodStepper(
                self.model,
                self.data,
                self._qpos_index,
                self._dof_index,
                self._head_id,
                Capsules.of_modules(self.model, self.robot.link_count),
            )
        except CompileError as exc:
            warnings.warn(
                f"the twin steps and reads its periods in Python, about 20 % slower: {exc}",
                RuntimeWarning,
                stacklevel=2,
            )
        self._layout = period_c.Layout(self.joint_count)
        self._restart_work()
        # Per joint: kp, kv and joint damping with torque on, and whether torque is on.
        self._kp, self._kv, self._damping = (np.zeros(self.joint_count) for _ in range(3))
        self._torque_mask = np.ones(self.joint_count, dtype=bool)
        self._store_gains(slice(None), self.robot.gains)
        self._apply_gains()
        self.data.ctrl[:] = 0.0
        hold_ctrl_history(self.model, self.data, self.data.ctrl)  # the straight pose's goals
        mujoco.mj_forward(self.model, self.data)
        self.torque_enabled = True
        self._pacer = Pacer(self.stats) if self._realtime else None
        physics = self.robot.servo.physics
        servo = servo_dynamics(physics, self.robot.gains)
        self._sensors = TwinSensors(
            self.model, self._head_id, physics.extras, physics.ticks.rad_per_tick, self._seed
        )
        extras = physics.extras
        if extras.stall_current_a is not None or extras.overload_trip_s is not None:
            self.electrics = ServoElectrics(
                physics, self.joint_count, servo.torque_limit_nm, servo.no_load_speed_rad_s
            )
        self._force_full = self.model.actuator_forcerange.copy()  # (N, 2): the servo's own
        self._force_limit = self._force_full.copy()  # under the torque caps, if any
        if self._torque_cap_nm is not None:
            self._apply_torque_caps()
        self.reset_physics_health()

    def reset(self, position_rad: np.ndarray | None = None) -> JointState:
        """Back to the start at once (Resettable): the model's start pose at rest (the origin,
        facing +x, or where the terrain starts it), the joints straight or at ``position_rad``
        (N,) rad with their goals there, time 0, the servos' electrical state and the
        physics-health account afresh. Gains and torque stay as they are. ValueError for a
        wrong shape."""
        self._require_connected()
        model, data = self.model, self.data
        mujoco.mj_resetData(model, data)
        self._torque_now = None
        self._period_state = self._period_body = None
        if position_rad is not None:
            pose = np.asarray(position_rad, dtype=float)
            if pose.shape != (self.joint_count,):
                raise ValueError(
                    f"reset pose has shape {pose.shape}, expected ({self.joint_count},) angles"
                )
            data.qpos[self._qpos_index] = pose
            data.ctrl[:] = pose
        else:
            data.ctrl[:] = 0.0
        hold_ctrl_history(model, data, data.ctrl)
        mujoco.mj_forward(model, data)
        self._restart_work()
        if self.electrics is not None:
            physics = self.robot.servo.physics
            servo = servo_dynamics(physics, self.robot.gains)
            self.electrics = ServoElectrics(
                physics, self.joint_count, servo.torque_limit_nm, servo.no_load_speed_rad_s
            )
            self.model.actuator_forcerange[:] = self._force_limit
            self._apply_gains()
        self.reset_physics_health()
        if self._pacer is not None:
            self._pacer = Pacer(self.stats)
        return self.read_state()

    def _restart_work(self) -> None:
        """Count each joint's positive work from zero; no period's readouts are current."""
        self._work_j = np.zeros(self.joint_count)
        if self._period is not None:
            self._period.restart(self._work_j)
        self._period_state = self._period_body = None

    def reset_physics_health(self, limits: HealthLimits | None = None) -> None:
        """Start the physics-health account afresh (a learning environment's new episode), with
        ``limits`` from now on when given, and the servos' electrical figures (energy, current,
        the distance the cost of transport counts) from here; the physics checks stay off
        where they are off."""
        if limits is not None:
            self._health_limits = limits
        if self.electrics is not None:
            self.electrics.restart_account()
        self._start_com = self.data.subtree_com[self._head_id].copy()
        if self._health_limits is None:
            return
        servo = servo_dynamics(self.robot.servo.physics, self.robot.gains)
        self.physics_monitor = HealthMonitor(
            self.model,
            Capsules.of_modules(self.model, self.robot.link_count),
            self._dof_index,
            self._head_id,
            no_load_speed_rad_s=servo.no_load_speed_rad_s,
            torque_limit_nm=servo.torque_limit_nm,
            limits=self._health_limits,
        )

    def _close(self) -> None:
        self.set_torque(self.stop_policy == "hold")

    # -- the cycle ---------------------------------------------------------------------------
    def _servo_torque(self) -> np.ndarray:
        """Each servo's output torque (N,), N·m: the drive less its back-EMF and gear damping."""
        if self._views:
            return servo_torque_nm(self._force_view, self._damping_view, self._qvel_view)
        dof = self._dof_at
        return servo_torque_nm(
            self.data.actuator_force, self.model.dof_damping[dof], self.data.qvel[dof]
        )

    def _read_state(self) -> JointState:
        data = self.data
        out = self._period_state
        if out is not None:  # the last period's readouts, if nothing has changed since
            self._period_state = None  # handed over once: no two states share one array
            if self._period_time_s == data.time:
                layout = self._layout
                position = out[layout.position]
                if self._sensors.alters_positions:
                    position = self._sensors.encoder_rad(position)
                return JointState(
                    time_s=float(data.time),
                    position_rad=position,
                    velocity_rad_s=out[layout.velocity],
                    effort_nm=out[layout.torque],
                    positive_work_j=self._work_j,  # the period's `total`: a new one each period
                )
        views = self._views
        velocity = (self._qvel_view if views else data.qvel[self._dof_at]).copy()
        # The torque the physics check took at the end of the last advance, if nothing has
        # stepped or changed the gains since (computing it once a cycle, not twice).
        effort = self._torque_now
        self._torque_now = None  # handed over once: no two states share one array
        if effort is None or self._torque_time_s != data.time:
            effort = self._servo_torque()
        position = (self._qpos_view if views else data.qpos[self._qpos_at]).copy()
        if self._sensors.alters_positions:
            position = self._sensors.encoder_rad(position)
        return JointState(
            time_s=float(data.time),
            position_rad=position,
            velocity_rad_s=velocity,
            effort_nm=effort,
            positive_work_j=self._work_j,  # never written in place: each period makes a new one
        )

    def _send_command(self, position_rad: np.ndarray) -> None:
        self._ctrl_view[:] = position_rad

    def _set_gains(self, gains: PDGains) -> None:
        self._store_gains(slice(None), gains)
        self._apply_gains()

    def _set_torque(self, enabled: bool) -> None:
        self._torque_mask[:] = enabled
        self._apply_gains()

    def set_joint_gains(self, joints: JointSelection, gains: PDGains) -> None:
        """Apply SI position-loop gains to some joints only.

        ``joints`` is a joint index, a slice, indices, or a (N,) bool mask (numpy indexing; an
        index out of range raises IndexError). Joints with torque off stay limp and take the
        gains when torque comes on.
        """
        self._require_connected()
        self._store_gains(joints, gains)
        self._apply_gains()

    def set_joint_torque(self, enabled: np.ndarray) -> None:
        """Torque on or off per joint (shape (N,) of bool), e.g. from emulated Torque Enable."""
        self._require_connected()
        self._torque_mask[:] = enabled
        self._apply_gains()
        self.torque_enabled = bool(np.all(enabled))

    def _store_gains(self, joints: JointSelection, gains: PDGains) -> None:
        servo = servo_dynamics(self.robot.servo.physics, gains)
        self._kp[joints] = servo.stiffness_nm_per_rad
        self._kv[joints] = servo.actuator_kv(float(self.model.opt.timestep))
        self._damping[joints] = servo.joint_damping_nms

    def _apply_gains(self) -> None:
        """Write each joint's kp/kv and damping, or none where its torque is off."""
        self._torque_now = None  # the damping changes the servo torque
        self._period_state = None  # and so the last period's torque readout
        mask = self._torque_mask
        kp, kv = self._kp, self._kv
        electrics = self.electrics
        if electrics is not None:
            mask = mask & ~electrics.tripped
            if electrics.battery_resistance_ohm is not None:  # the voltage sags with current
                ratio = electrics.voltage_ratio
                kp, kv = kp * ratio, kv * ratio
                self.model.actuator_forcerange[:] = self._force_limit * ratio
        kp = np.where(mask, kp, 0.0)
        # With torque off the H-bridge is open: no back-EMF braking, only gear friction remains.
        limp = self.robot.servo.physics.viscous_damping_nms
        damping = np.where(mask, self._damping, limp)
        kv = np.where(mask, kv, 0.0)
        if self._torque_cap_nm is not None:  # the damping inside the capped drive
            kv = kv + np.where(mask, damping, 0.0)
            damping = np.where(mask, 0.0, damping)
        self.model.actuator_gainprm[:, 0] = kp
        self.model.actuator_biasprm[:, 1] = -kp
        self.model.actuator_biasprm[:, 2] = -kv
        self.model.dof_damping[self._dof_index] = damping

    def limit_torque(self, torque_nm: npt.ArrayLike) -> None:
        """LimitsTorque: cap each servo's output torque at ``torque_nm`` (a scalar or (N,)
        N*m, > 0), as current-based position control caps its current: the servo still follows
        its goal, pushing with at most the cap (a cap above the stall torque changes nothing).
        Before connect it applies at connect. ValueError for a bad value.

        Uncapped, the output torque is the actuator's force less the joint's back-EMF damping
        at its speed. Capped, that damping is part of the actuator (its velocity gain), so the
        force range bounds the output torque itself: a current loop holds the current, and so
        the torque, at the cap whatever the speed, a joint driven backwards included."""
        self._torque_cap_nm = torque_caps(torque_nm, self.joint_count)
        if self.connected:
            self._apply_torque_caps()

    def _apply_torque_caps(self) -> None:
        cap = self._torque_cap_nm
        assert cap is not None
        self._force_limit = np.clip(self._force_full, -cap[:, None], cap[:, None])
        self.model.actuator_forcerange[:] = self._force_limit
        self._apply_gains()  # the damping moves into the capped drive (and the sag scales it)

    def send_command_unchecked(self, position_rad: np.ndarray) -> None:
        """Set goals (rad, (N,)) without the shape check: the emulator bridge's hot path."""
        self._ctrl_view[:] = position_rad

    def _advance(self, dt_s: float) -> None:
        steps = self._steps_per_period.get(dt_s) or self.steps_for(dt_s)
        period = self._period
        if period is None:
            self._advance_in_python(steps, dt_s)
            return
        # The period in C (period_c): steps, work, readouts and the health scan in one call.
        monitor, data, layout = self.physics_monitor, self.data, self._layout
        scan = monitor is not None and monitor.scans_in_c
        out = period.advance(steps, scan)
        if out[layout.unstable]:
            timestep = float(self.model.opt.timestep)
            raise diverged_error(float(out[layout.time_before]), steps, timestep, data.time)
        self._period_state = self._period_body = out
        self._period_time_s = data.time
        self._work_j = out[layout.total]
        if monitor is not None or self.electrics is not None:
            torque = out[layout.torque]  # read_state's effort too, unless changed since
            if monitor is not None:
                scanned = out[layout.scan] if scan else None
                monitor.sample(data, dt_s, torque, out[layout.work], scanned)
            if self.electrics is not None:
                self._update_electrics(dt_s, torque)
        if self._pacer is not None:
            self._pacer.wait(dt_s)

    def _advance_in_python(self, steps: int, dt_s: float) -> None:
        """``_advance`` without the compiled period: the same physics and readouts, bit for bit
        (tests/integration/twin/test_twin_period_c.py)."""
        self._step_check.start()
        work = self._step_integrating(steps)
        self._step_check.finish(steps)
        self._work_j = self._work_j + work
        if self.physics_monitor is not None or self.electrics is not None:
            torque = self._servo_torque()  # read_state's effort too, unless changed since
            self._torque_now, self._torque_time_s = torque, float(self.data.time)
            if self.physics_monitor is not None:
                self.physics_monitor.sample(self.data, dt_s, torque, work)
            if self.electrics is not None:
                self._update_electrics(dt_s, torque)
        if self._pacer is not None:
            self._pacer.wait(dt_s)

    def _step_integrating(self, steps: int) -> np.ndarray:
        """``steps`` physics steps without the compiled period; returns each joint's positive
        work over them (N,) J (``step_work_j``), one ``mj_step`` call per step keeping each
        step's actuator forces and joint speeds. The same physics as one
        ``mj_step(m, d, steps)`` call, bit for bit (MuJoCo loops over ``mj_step`` there too);
        the cost is in docs/benchmarks.md."""
        model, data = self.model, self.data
        if self._step_force.shape[0] < steps:
            self._step_force = np.zeros((steps, self.joint_count))
            self._step_velocity = np.zeros((steps, self.joint_count))
        forces, velocities = self._step_force[:steps], self._step_velocity[:steps]
        force = self._force_view
        views = self._views
        qvel = self._qvel_view if views else None
        step = mujoco.mj_step
        for k in range(steps):
            step(model, data)
            forces[k] = force
            velocities[k] = qvel if qvel is not None else data.qvel[self._dof_at]
        damping = self._damping_view if views else model.dof_damping[self._dof_at]
        return step_work_j(forces, damping, velocities, float(model.opt.timestep))

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
        self._steps_per_period[dt_s] = steps
        return steps

    def _update_electrics(self, dt_s: float, torque_nm: np.ndarray) -> None:
        """Currents, supply sag and overload after a period (``torque_nm`` the servos' output
        torque now); a trip limps the joint."""
        assert self.electrics is not None
        velocity = self.data.qvel[self._dof_index]
        trips = self.electrics.update(torque_nm, self.data.actuator_force, velocity, dt_s)
        if trips.any() or self.electrics.battery_resistance_ohm is not None:
            self._apply_gains()
        if trips.any() and self.raise_on_overload:
            joint = int(np.flatnonzero(trips)[0])
            raise ServoFaultError(
                self.robot.joints[joint].servo_id,
                ["Overload"],
                f"the twin's overload protection tripped at t={float(self.data.time):.4f} s "
                f"after {self.electrics.trip_s:g} s at the torque limit; torque is off",
            )

    def reset_overload(self, joints: np.ndarray) -> None:
        """Clear the overload of ``joints`` (bool (N,)), as rebooting those servos does."""
        self._require_connected()
        if self.electrics is not None:
            self.electrics.reset(np.asarray(joints, dtype=bool))
            self._apply_gains()

    @property
    def overloaded(self) -> np.ndarray:
        """Joints (bool (N,)) whose overload protection has tripped."""
        if self.electrics is None:
            return np.zeros(self.joint_count, dtype=bool)
        return self.electrics.tripped.copy()

    def physics_health(self) -> dict[str, object] | None:
        """The run's physics health so far (docs/physics.md), with the servos' electrical
        figures when the servo model has them; None with the checks off."""
        out = None if self.physics_monitor is None else self.physics_monitor.summary()
        if self.electrics is not None:
            com = self.data.subtree_com[self._head_id]
            distance = float(np.hypot(*(com[:2] - self._start_com[:2])))
            electrical = self.electrics.summary(self.robot.total_mass_kg, distance)
            out = {**(out or {}), **electrical}
        return out

    def head_gyro_rad_s(self) -> np.ndarray:
        """The head IMU's gyro (3,) rad/s in the head's frame, with the servo file's noise."""
        self._require_connected()
        return self._sensors.gyro_rad_s(self.data)

    def measured_torque_nm(self) -> np.ndarray:
        """SensesTorque: each servo's output torque (N,) N*m as of the last ``read_state`` (the
        servo model's, what a Present Current register would read); zeros before the first."""
        state = self.last_state
        if state is None:
            return np.zeros(self.joint_count)
        return state.effort_nm.copy()

    def _present_current_a(self) -> np.ndarray:
        """Each servo's current (N,) A, signed as its output torque: the torque over the
        torque constant (stall torque / ``stall_current_a``), the electrical model's draw."""
        assert self.electrics is not None
        torque = self._servo_torque()
        current: np.ndarray = torque / self.electrics.torque_constant_nm_per_a
        return current

    def body_state(self) -> BodyState:
        """Centre of mass of the whole snake and the head's orientation."""
        self._require_connected()
        out = self._period_body
        if out is not None:  # the last period's readouts, if nothing has stepped since
            self._period_body = None  # handed over once: no two body states share an array
            if self._period_time_s == self.data.time:
                layout = self._layout
                return BodyState(
                    com_m=out[layout.com],
                    head_quat=out[layout.quat],
                    head_gyro_rad_s=self._sensors.gyro_of(out[layout.angular], self.data),
                )
        return BodyState(
            com_m=self._com_view.copy(),
            head_quat=self._quat_view.copy(),
            head_gyro_rad_s=self._sensors.gyro_rad_s(self.data),
        )
