"""The cycle every learning environment steps: encoding -> gait -> safety layer -> twin.

It is ``snakebot run``'s cycle (``control/cycle.py``): the gait's targets at the current
phases go through the same ``SafetyLayer`` (joint limits, speed limit), ramped in as the run's
``CycleSchedule`` ramps, into the same twin backend (made through the backend registry),
``cycles_per_action`` times per policy action.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from snakebot.backends.registry import make_backend
from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.model_builder import link_name
from snakebot.config import RobotConfig, load_robot
from snakebot.control.cycle import CycleSchedule
from snakebot.control.metrics import head_yaw_rad
from snakebot.control.safety import SafetyLayer
from snakebot.errors import PhysicsHealthError
from snakebot.gaits.base import FloatArray
from snakebot.rl.encodings import Encoding, GaitClock, make_encoding
from snakebot.rl.settings import EnvSettings
from snakebot.types import BodyState, JointCommand, JointState


@dataclass(frozen=True)
class StepOutcome:
    """What one policy step did: COM before/after (3,) m, positive joint work J, the state.

    ``physics_health_error`` is the message of the hard physics-health limit (docs/physics.md)
    the twin crossed during the step, which then stopped early; None when it stayed credible.
    """

    com_before_m: FloatArray
    com_after_m: FloatArray
    positive_work_j: float
    state: JointState
    physics_health_error: str | None = None


class TwinLoop:
    """One connected twin of ``settings.robot`` driven through the safety layer."""

    def __init__(self, settings: EnvSettings, robot: RobotConfig | None = None) -> None:
        self.settings = settings
        self.robot = robot if robot is not None else load_robot(settings.robot)
        self.encoding: Encoding = make_encoding(
            settings.encoding,
            self.robot.joint_count,
            self.robot.lower_rad,
            self.robot.upper_rad,
            phase_hz=settings.phase_hz,
            dft_bins=settings.dft_bins,
        )
        self.clock = GaitClock(self.encoding)
        backend = make_backend(
            self.robot,
            "twin",
            timestep_s=settings.timestep_s,
            terrain=settings.terrain,
            friction_model=settings.friction_model,
        )
        assert isinstance(backend, TwinBackend)  # a robot file's twin (RobotConfig above)
        self.backend = backend
        self.backend.connect()
        self.safety = SafetyLayer.for_robot(self.robot)
        self.dt_s = 1.0 / settings.control_hz
        self.backend.steps_for(self.dt_s)  # a rate that is no whole number of steps fails here
        # The run's schedule: what ramps the amplitude in, as `snakebot run` ramps it.
        self.schedule = CycleSchedule(settings.control_hz, ramp_s=self.safety.ramp_s)
        self._tail_id = self.backend.model.body(link_name(self.robot.link_count - 1)).id
        self._head_id = self.backend.model.body(link_name(0)).id
        self.state = self.backend.read_state()

    @property
    def body_length_m(self) -> float:
        """The robot's length, the task's unit of distance."""
        return float(self.robot.body_length_m)

    def reset(self, phase_rad: float) -> JointState:
        """Straight snake at rest at the origin, facing +x; the phases start at ``phase_rad``."""
        self.state = self.backend.reset()  # Resettable: physics health afresh too
        self.clock.reset(phase_rad)
        self.safety.reset(self.state.position_rad)
        return self.state

    def step(self, action: FloatArray) -> StepOutcome:
        """Play ``action`` for one policy period; returns what moved.

        A hard physics-health limit crossed on the way ends the step at that cycle, named in
        the outcome (the episode cannot go on credibly; training can).
        """
        gait = self.encoding.gait(action)
        backend, safety, clock, dt = self.backend, self.safety, self.clock, self.dt_s
        com_before = self.body().com_m
        work = 0.0
        for _ in range(self.settings.cycles_per_action):
            target = clock.targets(gait)
            command = safety.filter(target, dt, self.schedule.ramp_in(self.state.time_s))
            backend.send_command(JointCommand(command))
            try:
                backend.advance(dt)
            except PhysicsHealthError as exc:
                self.state = backend.read_state()
                return StepOutcome(com_before, self.body().com_m, work, self.state, str(exc))
            state = backend.read_state()
            # Robot time, as the runner's gait time: a policy played by `run` turns its phases
            # by the same float differences.
            clock.advance(gait, state.time_s - self.state.time_s)
            self.state = state
            power = state.effort_nm * state.velocity_rad_s
            work += float(power[power > 0].sum()) * dt
        return StepOutcome(com_before, self.body().com_m, work, self.state)

    def body(self) -> BodyState:
        """COM (3,) m and head orientation, from the twin."""
        return self.backend.body_state()

    def heading_rad(self) -> float:
        """The body's mean heading: the direction from the tail module to the head module."""
        xpos = self.backend.data.xpos
        dx, dy = (xpos[self._head_id, :2] - xpos[self._tail_id, :2]).tolist()
        return math.atan2(dy, dx)

    def head_yaw_rad(self) -> float:
        """The head module's yaw in the world frame."""
        return head_yaw_rad(self.backend.data.xquat[self._head_id])

    def close(self) -> None:
        """Release the twin."""
        self.backend.close()
