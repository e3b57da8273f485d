"""The MuJoCo twin as a Backend: same commands and states as the servo chain, physics inside."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

import mujoco
import numpy as np

from snakebot.backends.base import Backend, BodyState, JointState, ServoGains
from snakebot.backends.pacing import Pacer
from snakebot.backends.twin.cliff import Cliff
from snakebot.backends.twin.friction.scale import FrictionModel
from snakebot.backends.twin.model_builder import (
    GroundFriction,
    build_model,
    hold_ctrl_history,
    joint_name,
    link_name,
)
from snakebot.backends.twin.servo_model import servo_dynamics
from snakebot.backends.twin.terrain import Terrain, as_terrain
from snakebot.config.schema import RobotConfig
from snakebot.errors import ConfigError, SimulationDivergedError

JointSelection = int | slice | Sequence[int] | np.ndarray
"""Joints by numpy indexing: one index, a slice, indices, or a (N,) bool mask."""


class Simulated(Protocol):
    """A backend with a MuJoCo model and data to render or view (the twin, a soft body)."""

    model: mujoco.MjModel
    data: mujoco.MjData


# MuJoCo answers instability by resetting the state and counting a warning, not with NaN.
_BAD_WARNINGS = np.array(
    [
        mujoco.mjtWarning.mjWARN_BADQACC,
        mujoco.mjtWarning.mjWARN_BADQPOS,
        mujoco.mjtWarning.mjWARN_BADQVEL,
    ],
    dtype=int,
)


class TwinBackend(Backend):
    """Steps a MuJoCo model of ``robot``; as fast as possible, or paced to the wall clock.

    ``friction`` overrides the robot's ground model (``--friction``); ``timestep_s`` overrides
    ``twin.timestep_s``; ``terrain`` (a Terrain, a Cliff, ``--terrain`` text such as
    ``"pegs:density=12"``, or None for flat) sets the ground and the start pose;
    ``friction_model`` ("auto", "pairs", "scale"; None: the robot file's) how the ground's
    friction is made. A bad terrain raises ConfigError here, naming the key.
    Control periods passed to ``advance`` must be whole numbers of steps.
    """

    def __init__(
        self,
        robot: RobotConfig,
        *,
        friction: GroundFriction | None = None,
        timestep_s: float | None = None,
        realtime: bool = False,
        terrain: Terrain | Cliff | str | None = None,
        friction_model: FrictionModel | None = None,
    ) -> None:
        super().__init__()
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
        self._steps_per_period: dict[float, int] = {}

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
        joint_ids = [self.model.joint(joint_name(i)).id for i in range(self.joint_count)]
        self._qpos_index = np.array([self.model.jnt_qposadr[j] for j in joint_ids])
        self._dof_index = np.array([self.model.jnt_dofadr[j] for j in joint_ids])
        self._head_id = self.model.body(link_name(0)).id
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

    def _close(self) -> None:
        self.set_torque(self.stop_policy == "hold")

    # -- the cycle ---------------------------------------------------------------------------
    def _read_state(self) -> JointState:
        data = self.data
        velocity = data.qvel[self._dof_index].copy()
        effort = data.actuator_force.copy() - self.model.dof_damping[self._dof_index] * velocity
        return JointState(
            time_s=float(data.time),
            position_rad=data.qpos[self._qpos_index].copy(),
            velocity_rad_s=velocity,
            effort_nm=effort,
        )

    def _send_command(self, position_rad: np.ndarray) -> None:
        self.data.ctrl[:] = position_rad

    def _set_gains(self, gains: ServoGains) -> None:
        self._store_gains(slice(None), gains)
        self._apply_gains()

    def _set_torque(self, enabled: bool) -> None:
        self._torque_mask[:] = enabled
        self._apply_gains()

    def set_joint_gains(self, joints: JointSelection, gains: ServoGains) -> None:
        """Apply position-loop gains (servo register units) to some joints only.

        ``joints`` is a joint index, a slice, indices, or a (N,) bool mask (numpy indexing; an
        index out of range raises IndexError). Joints with torque off stay limp and take the
        gains when torque comes on. The I gain is ignored: the twin's loop is PD.
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

    def _store_gains(self, joints: JointSelection, gains: ServoGains) -> None:
        servo = servo_dynamics(self.robot.servo.physics, gains)
        self._kp[joints] = servo.stiffness_nm_per_rad
        self._kv[joints] = servo.actuator_kv(float(self.model.opt.timestep))
        self._damping[joints] = servo.joint_damping_nms

    def _apply_gains(self) -> None:
        """Write each joint's kp/kv and damping, or none where its torque is off."""
        mask = self._torque_mask
        kp = np.where(mask, self._kp, 0.0)
        self.model.actuator_gainprm[:, 0] = kp
        self.model.actuator_biasprm[:, 1] = -kp
        self.model.actuator_biasprm[:, 2] = -np.where(mask, self._kv, 0.0)
        # With torque off the H-bridge is open: no back-EMF braking, only gear friction remains.
        limp = self.robot.servo.physics.viscous_damping_nms
        self.model.dof_damping[self._dof_index] = np.where(mask, self._damping, limp)

    def send_command_unchecked(self, position_rad: np.ndarray) -> None:
        """Set goals (rad, (N,)) without the shape check: the emulator bridge's hot path."""
        self.data.ctrl[:] = position_rad

    def _advance(self, dt_s: float) -> None:
        steps = self._steps_per_period.get(dt_s) or self.steps_for(dt_s)
        warnings = self.data.warning.number
        before = int(warnings[_BAD_WARNINGS].sum())
        mujoco.mj_step(self.model, self.data, steps)
        if int(warnings[_BAD_WARNINGS].sum()) != before:
            raise SimulationDivergedError(
                float(self.data.time), "MuJoCo reported bad accelerations (state was reset)"
            )
        if self._pacer is not None:
            self._pacer.wait(dt_s)

    def steps_for(self, dt_s: float) -> int:
        """Physics steps in a control period; it must be a whole number of timesteps."""
        timestep = float(self.model.opt.timestep)
        steps = round(dt_s / timestep)
        if steps < 1 or not math.isclose(steps * timestep, dt_s, rel_tol=1e-6):
            raise ConfigError(
                "--rate",
                "",
                f"control period {dt_s:g} s is not a whole number of {timestep:g} s physics "
                f"steps; pick a rate that divides {1 / timestep:g} Hz (e.g. 50, 100, 250)",
            )
        self._steps_per_period[dt_s] = steps
        return steps

    def body_state(self) -> BodyState:
        """Centre of mass of the whole snake and the head's orientation."""
        self._require_connected()
        return BodyState(
            com_m=self.data.subtree_com[self._head_id].copy(),
            head_quat=self.data.xquat[self._head_id].copy(),
        )
