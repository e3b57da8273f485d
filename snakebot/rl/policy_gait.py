"""A trained policy played as a gait: ``snakebot run --policy DIR``.

``PolicyGait`` is a ``Gait`` the runner drives like any other, through the same safety layer and
telemetry. It is the environments' ``ActionGait`` (snakebot.rl.action_gait) deciding its own
actions: every 1/action_hz s of gait time it builds the observation the environment built, asks
the policy for an action and holds it; in between it plays that action's gait at the phases it
integrates, once per control cycle, exactly as the env's cycles do (the same gait class in the
same ``CycleLoop``).

Pose source. A velocity policy observes only the servos. A goal policy also needs the snake's
centre of mass and heading every step: anything with a ``body_state() -> BodyState | None``
method (``PoseSource``) provides them. A backend that senses the body (``SensesBody``: the twin)
is one; a motion-capture rig or an
odometry estimate can be another (see docs/learning.md, "Pose sources"). On a backend with no
pose (the servo bus) a goal policy is refused, saying why.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Protocol

import numpy as np
import numpy.typing as npt

from snakebot.backends.base import Backend
from snakebot.backends.capabilities import SensesBody
from snakebot.config import RobotConfig
from snakebot.control.metrics import head_yaw_rad
from snakebot.errors import ConfigError, GaitError
from snakebot.gaits.base import FloatArray
from snakebot.rl.action_gait import ActionGait
from snakebot.rl.encodings import make_encoding
from snakebot.rl.observe import goal_observation, velocity_observation
from snakebot.rl.policy_file import PolicyFile, check_env_id
from snakebot.rl.settings import (
    GOAL_ENV_ID,
    VELOCITY_ENV_ID,
    EnvSettings,
    GoalSettings,
    VelocitySettings,
    split_kwargs,
)
from snakebot.types import BodyState, JointState

StateReader = Callable[[], JointState]


class PoseSource(Protocol):
    """Where a goal policy gets the snake's pose: centre of mass (world frame, m) and the head's
    orientation, as ``BodyState``; None when the pose is not known right now."""

    def body_state(self) -> BodyState | None:
        """The pose now."""


def state_reader(backend: Backend) -> StateReader:
    """The joint state the runner read last (every backend keeps it: ``last_state``), so no
    extra bus transaction; a read before the first cycle's."""

    def read() -> JointState:
        last = backend.last_state
        return last if last is not None else backend.read_state()

    return read


class PolicyGait(ActionGait):
    """The policy in ``policy`` as a closed-loop gait for ``robot``.

    ``command``: for a velocity policy (speed m/s, turn rate rad/s); for a goal policy the goal
    (x, y) in m from the centre of mass at the first step, in the head's frame then (x forward).
    ``read_state`` gives the measured joint state; ``pose`` is the goal policy's pose source.
    Raises ConfigError when the policy does not fit the robot, or a goal policy has no pose.
    """

    def __init__(
        self,
        policy: PolicyFile,
        robot: RobotConfig,
        read_state: StateReader,
        command: tuple[float, float],
        *,
        pose: PoseSource | None = None,
    ) -> None:
        source = policy.folder
        self.goal_task = policy.env_id == GOAL_ENV_ID
        check_env_id(source, policy.env_id)
        task_class = GoalSettings if self.goal_task else VelocitySettings
        settings, task = split_kwargs(dict(policy.env_kwargs), task_class)
        self.settings: EnvSettings = settings
        self.task = task
        if self.goal_task and pose is None:
            raise ConfigError(
                source,
                "",
                "a SnakeGoal policy observes the goal from the snake's pose (centre "
                "of mass and heading) every step; this backend has no pose source (the servos "
                "report joints only). Play it on the twin (backend sim), train a "
                "SnakeVelocity policy for the bus, or plug in a pose source (docs/learning.md, "
                "'Pose sources')",
            )
        self.joint_count = robot.joint_count
        if settings.robot not in (robot.name, str(robot.source)):
            raise ConfigError(
                source,
                "env_kwargs.robot",
                f"the policy was trained on {settings.robot!r}, not {robot.name!r}",
            )
        encoding = make_encoding(
            settings.encoding,
            robot.joint_count,
            robot.lower_rad,
            robot.upper_rad,
            phase_hz=settings.phase_hz,
            dft_bins=settings.dft_bins,
        )
        if policy.actor.action_dim != encoding.action_dim:
            raise ConfigError(
                source,
                "actor.npz",
                f"the actor gives {policy.actor.action_dim} "
                f"actions, the {settings.encoding} encoding takes "
                f"{encoding.action_dim}",
            )
        super().__init__(encoding)
        self.policy = policy
        self.robot = robot
        self.read_state = read_state
        self.pose = pose
        self.user_command = (float(command[0]), float(command[1]))
        if not all(math.isfinite(v) for v in self.user_command):
            raise ConfigError("command", "", f"expected two finite numbers, got {command}")
        self.decisions = 0
        self.goal_xy_m: FloatArray | None = None
        self._next_decision_s = 0.0
        self._check_obs_size()

    def _check_obs_size(self) -> None:
        phases = 2 * self.encoding.observed_phases
        n = self.joint_count
        expected = 2 * n + phases + 2 if self.goal_task else 3 * n + phases + 2
        if self.policy.actor.obs_dim != expected:
            raise ConfigError(
                self.policy.folder,
                "actor.npz",
                f"the actor reads "
                f"{self.policy.actor.obs_dim} observations, this robot and "
                f"encoding give {expected}",
            )

    @property
    def uses_measured_pose(self) -> bool:
        """Closed loop: it reads the servos."""
        return True

    def reset(self) -> None:
        """Start afresh: phases at 0, a decision due at once, the goal set at the first one."""
        super().reset()
        self.decisions = 0
        self.goal_xy_m = None
        self._next_decision_s = 0.0

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """Not defined: a policy's targets depend on what the servos measure as it runs."""
        raise GaitError(
            "a policy is a closed-loop gait: its targets exist only as it runs "
            "(use command(), as the runner does)"
        )

    def command(self, time_s: float, measured_rad: FloatArray | None = None) -> FloatArray:
        """Targets (N,) in rad for gait time ``time_s``; a new action every 1/action_hz s."""
        self.advance_to(time_s)  # the phases of now, which the observation holds
        # Half a control period of slack: gait times are sums of floats.
        if self.held is None or time_s >= self._next_decision_s - 1e-6:
            # float32, as the env's action space hands actions over in training
            action = self.policy.actor(self.observation()).astype(np.float32)
            self.hold(action.astype(np.float64))
            self.decisions += 1
            period = 1.0 / self.settings.action_hz
            self._next_decision_s = max(self._next_decision_s + period, time_s + 0.5 * period)
        return super().command(time_s)

    def observation(self) -> np.ndarray:
        """What the env would observe now."""
        robot = self.robot
        limits = (robot.lower_rad, robot.upper_rad)
        state = self.read_state()
        if not self.goal_task:
            scale = np.array(
                [
                    max(abs(v) for v in self.task.speed_range_mps) or 1.0,
                    max(abs(v) for v in self.task.turn_range_rad_s) or 1.0,
                ]
            )
            return velocity_observation(
                state,
                self.clock.observed(),
                np.array(self.user_command),
                limits,
                float(robot.max_speed_rad_s),
                robot.servo.physics.stall_torque_nm,
                scale,
            )
        assert self.pose is not None
        body = self.pose.body_state()
        if body is None:
            raise GaitError("the pose source has no pose now; a goal policy cannot go on")
        if self.goal_xy_m is None:
            yaw = head_yaw_rad(body.head_quat)
            x, y = self.user_command
            offset = np.array(
                [x * math.cos(yaw) - y * math.sin(yaw), x * math.sin(yaw) + y * math.cos(yaw)]
            )
            self.goal_xy_m = body.com_m[:2] + offset
        return goal_observation(
            state,
            body,
            self.goal_xy_m,
            self.clock.observed(),
            limits,
            float(robot.max_speed_rad_s),
            float(robot.body_length_m),
        )


def policy_gait_for_backend(
    folder: str,
    robot: RobotConfig,
    backend: Backend,
    command: tuple[float, float] | None,
    rate_hz: float,
    *,
    pose: PoseSource | None = None,
) -> tuple[str, PolicyGait]:
    """The policy in ``folder`` as a gait on ``backend`` (not yet connected), and its name for
    the run summary. The backend is the goal policy's pose source when it knows the pose and no
    other ``pose`` is given. ConfigError when something does not fit (saying what)."""
    from pathlib import Path

    from snakebot.rl.policy_file import load_policy

    policy = load_policy(Path(folder))
    if command is None:
        what = (
            "speed,turn_rate (m/s, rad/s)"
            if policy.env_id == VELOCITY_ENV_ID
            else "goal X,Y (m, from the snake, X forward)"
        )
        raise ConfigError("command", "", f"the policy in {folder} needs a command: {what}")
    action_hz = float(policy.env_kwargs.get("action_hz", EnvSettings.action_hz))
    if rate_hz < action_hz:
        raise ConfigError(
            "rate_hz",
            "",
            f"the policy acts at {action_hz:g} Hz; run the "
            f"control loop at least that fast (e.g. 100 Hz)",
        )
    if pose is None and isinstance(backend, SensesBody):
        pose = backend
    gait = PolicyGait(policy, robot, state_reader(backend), command, pose=pose)
    kind = "goal" if gait.goal_task else "velocity"
    return f"policy:{kind}:{gait.settings.encoding}", gait
