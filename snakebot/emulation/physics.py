"""Hardware in the loop without hardware: emulated servos whose shafts are the twin's joints.

Goal Position, Torque Enable, the Position P/D Gain registers and, in current-based position control
(Operating Mode 5), Goal Current (the twin's actuator force capped at kt * |Goal Current|), read
from each virtual servo's control table, drive the MuJoCo twin of the same robot (its joint
stiffness and damping follow the registers through the servo's `GainMapping`, as on the real chain;
the twin has no I term, so Position I Gain is ignored); Present Position/Velocity/Load come back
from the twin. Time is the chain's: a pty server advances the chain by wall-clock time, so the twin
runs in real time.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from snakebot.backends.twin.backend import TwinBackend
from snakebot.backends.twin.health import HealthLimits
from snakebot.config.schema import RobotConfig
from snakebot.control.metrics import RunMetrics, cycle_work_j
from snakebot.emulation.alarms import Fault
from snakebot.emulation.chain import EmulatedChain, make_chain_for_ids
from snakebot.emulation.motion import MotorState, OperatingMode, ServoCommand
from snakebot.emulation.virtual_servo import VirtualServo

if TYPE_CHECKING:
    from snakebot.backends.twin.friction.scale import FrictionModel
    from snakebot.backends.twin.terrain import Terrain


class TwinMotion:
    """A `MotionModel` shared by every servo of the chain, backed by one `TwinBackend`.

    The first servo's step of each chain step (`EmulatedChain.settle`) applies what changed in
    the control tables (goals, torque, gains), steps the twin by the elapsed time (whole physics
    steps; the remainder carries over) and writes every servo's state.
    """

    def __init__(self, robot: RobotConfig, twin: TwinBackend) -> None:
        self.robot = robot
        self.twin = twin
        self.metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
        self._index = {joint.servo_id: i for i, joint in enumerate(robot.joints)}
        self._direction = np.array([j.direction for j in robot.joints], dtype=float)
        self._zero = np.array([j.zero_offset_rad for j in robot.joints])
        self._goal = np.zeros(robot.joint_count)
        self._torque = np.zeros(robot.joint_count, dtype=bool)
        self._commands: dict[int, ServoCommand] = {}  # per joint, the command last applied
        self._gains: dict[int, tuple[int, ...]] = {}
        self._pending_s = 0.0
        self._leader: VirtualServo | None = None
        self._servos: dict[int, VirtualServo] = {}
        self.steps = 0
        self._latched: set[int] = set()  # joints whose servo latched the twin's overload
        self._start_height_m = self._top_height_m = 0.0  # centre of mass, m (from attach)
        # Current-based position (Operating Mode 5): Goal Current caps the torque, kt * |I|.
        physics = robot.servo.physics
        self._stall_nm = physics.stall_torque_nm
        self._cap_nm = np.full(robot.joint_count, physics.stall_torque_nm)

    def attach(self, chain: EmulatedChain) -> None:
        """Remember the chain's servos (by joint), make the twin follow their registers from the
        start (boot torque, factory gains), and start the scored window."""
        self._servos = {
            self._index[s.servo_id]: s for s in chain.servos if s.servo_id in self._index
        }
        self._leader = chain.servos[0]
        self.twin.set_torque(False)
        self._torque[:] = False
        self._commands.clear()
        self._gains.clear()
        self._read_tables()
        self._last_state = self.twin.read_state()
        body = self.twin.body_state()
        self.metrics.start(self._last_state.time_s, body)
        self._start_height_m = self._top_height_m = float(body.com_m[2])
        self._publish()

    def hold(self) -> None:
        """The servos hold where the twin stands, as servos a person powered and wrapped by
        hand: Torque Enable 1 and Goal Position = Present Position on every servo, taken up by
        the twin before any physics step."""
        for servo in self._servos.values():
            servo.poke("goal_position", servo.peek("present_position"))
            servo.poke("torque_enable", 1)
        self._read_tables()

    def step(self, servo: VirtualServo, dt_s: float) -> None:
        """Advance the twin once per chain step (on the first servo's step); a closed twin
        leaves the servos where it last put them."""
        if servo is not self._leader or not self.twin.connected:
            return
        self._read_tables()
        self._pending_s += dt_s
        timestep = float(self.twin.model.opt.timestep)
        steps = math.floor(self._pending_s / timestep + 1e-9)
        if steps < 1:
            return
        self._pending_s -= steps * timestep
        self.twin.advance(steps * timestep)
        self.steps += 1
        self._latch_overloads()
        state = self.twin.read_state()
        work = cycle_work_j(self._last_state, state)
        self._last_state = state
        body = self.twin.body_state()
        self.metrics.add(self._goal, state, body, steps * timestep, work)
        self._top_height_m = max(self._top_height_m, float(body.com_m[2]))
        self._publish()

    def _latch_overloads(self) -> None:
        """A joint whose twin servo tripped its overload protection latches Overload in its
        servo's Hardware Error Status; a servo rebooted since (no error latched) clears it."""
        tripped = self.twin.overloaded
        if not tripped.any():
            return
        cleared = np.zeros_like(tripped)
        for index, servo in self._servos.items():
            if not tripped[index]:
                continue
            if index in self._latched and not servo.hardware_error:
                cleared[index] = True  # rebooted: the latch is gone
                self._latched.discard(index)
            elif index not in self._latched:
                servo.latch_fault(Fault.OVERLOAD)
                self._latched.add(index)
        if cleared.any():
            self.twin.reset_overload(cleared)

    def _read_tables(self) -> None:
        """Apply the goals, torque flags and gains of every servo whose table changed."""
        goals_changed = torque_changed = caps_changed = False
        new_gains: dict[tuple[int, ...], list[int]] = {}
        gain_keys = self.robot.servo.gain_keys  # P/I/D or Compliance Slope, as the model has
        for index, servo in self._servos.items():
            command = servo.command()  # cached until the servo's memory changes
            if command is self._commands.get(index):
                continue
            self._commands[index] = command
            goals_changed = True
            # The servo's frame: motor = direction * (joint + zero offset); see ServoChainBackend.
            self._goal[index] = (
                self._direction[index] * command.goal_position_rad - self._zero[index]
            )
            if command.torque_enabled != self._torque[index]:
                self._torque[index] = command.torque_enabled
                torque_changed = True
            cap = self._stall_nm
            if command.operating_mode == OperatingMode.CURRENT_BASED_POSITION:
                stall_a = servo.table.specs.stall_current_a
                cap = min(cap, abs(command.goal_current_a) / stall_a * self._stall_nm)
            if cap != self._cap_nm[index]:
                self._cap_nm[index] = cap
                caps_changed = True
            gains = tuple(servo.memory.get(key) for key in gain_keys)
            if gains != self._gains.get(index):
                self._gains[index] = gains
                new_gains.setdefault(gains, []).append(index)
        for values, joints in new_gains.items():
            gains_si = self.robot.servo.gains_from(dict(zip(gain_keys, values, strict=True)))
            self.twin.set_joint_gains(joints, gains_si)
        if caps_changed:
            # A Goal Current of 0 still holds a little (one register unit's worth, not none).
            self.twin.limit_torque(np.maximum(self._cap_nm, 1e-3 * self._stall_nm))
        if torque_changed:
            self.twin.set_joint_torque(self._torque)
        if goals_changed:
            goal = np.clip(self._goal, self.robot.lower_rad, self.robot.upper_rad)
            self.twin.send_command_unchecked(goal)

    def _publish(self) -> None:
        state = self.twin.read_state()
        stall = self.robot.servo.physics.stall_torque_nm
        for index, servo in self._servos.items():
            direction = self._direction[index]
            old = servo.state
            effort = float(np.clip(direction * state.effort_nm[index] / stall, -1.0, 1.0))
            servo.state = MotorState(
                position_rad=float(direction * (state.position_rad[index] + self._zero[index])),
                velocity_rad_s=float(direction * state.velocity_rad_s[index]),
                effort=effort,
                current_a=effort * servo.table.specs.stall_current_a,
                input_voltage_v=old.input_voltage_v,
                temperature_c=old.temperature_c,
            )

    def summary(self) -> dict[str, object]:
        """The twin's run summary, with the same keys as ``snakebot run --json``."""
        out = self.metrics.summary(None)
        elapsed = float(out["duration_s"])  # type: ignore[arg-type]
        out["rate_hz"] = None
        out["achieved_rate_hz"] = self.steps / elapsed if elapsed > 0 else 0.0
        out["overruns"] = 0
        out["interrupted"] = False
        # How high the centre of mass got above where it started (m, and in body lengths):
        # a climb shows here, though a run's ramp-out lets the snake down again.
        rise = self._top_height_m - self._start_height_m
        out["max_rise_m"] = rise
        out["max_rise_body_lengths"] = rise / self.robot.body_length_m
        physics = self.twin.physics_health()
        if physics is not None:
            out["physics"] = physics
        return out


def make_twin_chain(
    robot: RobotConfig,
    baud: int,
    *,
    terrain: Terrain | str | None = None,
    friction_model: FrictionModel | None = None,
    wrapped_pose_rad: np.ndarray | None = None,
) -> tuple[EmulatedChain, TwinMotion]:
    """The robot's servo chain at ``baud``, every servo backed by one connected twin on
    ``terrain`` (a Terrain or its spec, e.g. ``"pegs:density=100,seed=1"``; None: the flat
    floor) with ``friction_model`` (None: the robot file's). With ``wrapped_pose_rad`` (N,) rad
    the twin starts coiled in that pose around the pole terrain's pole (``wrap_on_pole``) and
    the servos boot holding it (torque on, Goal Position where they stand), as CMU's snakes are
    wrapped by hand. ConfigError for a bad terrain, or a wrapped start without a pole."""
    # The servo latches an overload instead; a bus keeps answering whatever the physics does,
    # so physics health is reported in the summary, never raised.
    twin = TwinBackend(
        robot,
        raise_on_overload=False,
        health=HealthLimits(hard=False),
        terrain=terrain,
        friction_model=friction_model,
    )
    twin.connect()
    if wrapped_pose_rad is not None:
        from snakebot.backends.twin.pole_wrap import wrap_on_pole

        wrap_on_pole(twin, wrapped_pose_rad)
    motion = TwinMotion(robot, twin)
    chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud, motion=motion)
    motion.attach(chain)
    if wrapped_pose_rad is not None:
        motion.hold()
    return chain, motion
