"""The twin side of every learning environment: ``snakebot run``'s cycle, not a copy of it.

A policy step plays the action through a ``CycleLoop`` (``control/loop.py``, the loop
``run_gait`` steps): an ``ActionGait`` holds the action for ``cycles_per_action`` cycles, each
one the runner's gait cycle (targets at the integrated phases, the ``SafetyLayer``'s joint and
speed limits, the ``CycleSchedule``'s amplitude ramp, the twin stepped one control period,
``RunMetrics`` accounting it). A new episode starts from the twin's own reset (``Resettable``).
Nothing here sends a command or steps physics itself, so the env's episodes are what
``snakebot run --policy`` plays, by construction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from snakebot.backends.capabilities import Resettable
from snakebot.backends.registry import make_backend
from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.model_builder import link_name
from snakebot.config import RobotConfig, load_robot
from snakebot.control.cycle import CycleSchedule, GaitCycle
from snakebot.control.loop import CycleLoop
from snakebot.control.metrics import RunMetrics, head_yaw_rad
from snakebot.control.safety import SafetyLayer
from snakebot.errors import PhysicsHealthError
from snakebot.gaits.base import FloatArray
from snakebot.rl.action_gait import ActionGait
from snakebot.rl.encodings import Encoding, GaitClock, make_encoding
from snakebot.rl.settings import EnvSettings
from snakebot.types import BodyState, JointState


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


class TwinEpisode:
    """One connected twin of ``settings.robot`` and the ``CycleLoop`` of its current episode."""

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
        self.gait = ActionGait(self.encoding)
        backend = make_backend(
            self.robot,
            "twin",
            timestep_s=settings.timestep_s,
            terrain=settings.terrain,
            friction_model=settings.friction_model,
        )
        assert isinstance(backend, TwinBackend)  # a robot file's twin (RobotConfig above)
        assert isinstance(backend, Resettable)
        self.backend = backend
        self.backend.connect()
        self.safety = SafetyLayer.for_robot(self.robot)
        self.backend.steps_for(1.0 / settings.control_hz)  # a rate with no whole number of steps
        # The run's schedule: what ramps the amplitude in, as `snakebot run` ramps it.
        self.schedule = CycleSchedule(
            settings.control_hz,
            ramp_s=self.safety.ramp_s,
            timestep_s=float(self.backend.model.opt.timestep),
        )
        self._tail_id = self.backend.model.body(link_name(self.robot.link_count - 1)).id
        self._head_id = self.backend.model.body(link_name(0)).id
        self.metrics: RunMetrics
        self.cycles: CycleLoop
        self.state: JointState
        self.reset(0.0)

    @property
    def clock(self) -> GaitClock:
        """The phases the actions are played at."""
        return self.gait.clock

    @property
    def dt_s(self) -> float:
        """The control period, s."""
        return self.schedule.period_s

    @property
    def body_length_m(self) -> float:
        """The robot's length, the task's unit of distance."""
        return float(self.robot.body_length_m)

    def reset(self, phase_rad: float) -> JointState:
        """Straight snake at rest at the origin, facing +x; the phases start at ``phase_rad``.

        The twin resets itself (``Resettable``: pose, time 0, physics health afresh) and a new
        episode's ``CycleLoop`` starts from the pose it measures, as ``run_gait`` starts.
        """
        self.backend.reset()
        self.gait.start_phase_rad = phase_rad
        robot = self.robot
        self.metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
        # The body (COM, heading) is read at policy steps, where the task needs it; per cycle
        # the metrics account the joints only (the positive work).
        self.cycles = CycleLoop(
            self.backend,
            GaitCycle([self.gait], self.safety),
            self.schedule,
            self.metrics,
            read_body=False,
        )
        self.cycles.start()  # the gait (phases) and the safety layer from the measured pose
        self.state = self.cycles.state
        return self.state

    def step(self, action: FloatArray) -> StepOutcome:
        """Play ``action`` for one policy period; returns what moved.

        A hard physics-health limit crossed on the way ends the step at that cycle, named in
        the outcome (the episode cannot go on credibly; training can).
        """
        cycles, metrics = self.cycles, self.metrics
        self.gait.hold(action)
        com_before = self.body().com_m
        work_before = metrics.positive_work_j
        error: str | None = None
        for _ in range(self.settings.cycles_per_action):
            try:
                cycles.gait_step()
            except PhysicsHealthError as exc:
                error = str(exc)
                break
        if error is None:
            self.state = cycles.state
            # The phases of now, as the next action sees them (PolicyGait turns them before it
            # decides, as here).
            self.gait.advance_to(cycles.elapsed_s)
        else:
            self.state = self.backend.read_state()
        work = metrics.positive_work_j - work_before
        return StepOutcome(com_before, self.body().com_m, work, self.state, error)

    def body(self) -> BodyState:
        """COM (3,) m and head orientation, from the twin."""
        return self.backend.body_state()

    def heading_rad(self) -> float:
        """The body's mean heading: the direction from the tail module to the head module."""
        xpos = self.backend.data.xpos
        dx, dy = (xpos[self._head_id, :2] - xpos[self._tail_id, :2]).tolist()
        return math.atan2(dy, dx)

    def head_xy_m(self) -> FloatArray:
        """The head module's centre (2,) in the world frame, m."""
        return np.array(self.backend.data.xpos[self._head_id, :2], dtype=np.float64)

    def head_yaw_rad(self) -> float:
        """The head module's yaw in the world frame."""
        return head_yaw_rad(self.backend.data.xquat[self._head_id])

    def close(self) -> None:
        """Release the twin."""
        self.backend.close()
