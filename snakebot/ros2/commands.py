"""Commands from ROS to the control cycle: what the callbacks leave, and the gait that plays it.

The ROS callbacks run on the executor's thread; they only turn messages into the commands
below and leave the newest in a :class:`CommandInbox`. The control loop takes what is there
once a cycle (snakebot.ros2.serve) and :class:`CommandDriver` hands it to the gait: a steer
(``cmd_vel``) to the live gait through ``snakebot drive``'s own controller, joint targets and
trajectories to :class:`CommandedGait`. Whatever the gait makes, the loop's safety layer then
clips, slew-limits and ramps. Nothing here imports rclpy.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
import numpy.typing as npt

from snakebot.drive.controller import DriveController, GaitChoice
from snakebot.errors import GaitError, SnakebotError
from snakebot.gaits.base import Gait
from snakebot.gaits.live import LiveGait

FloatArray = npt.NDArray[np.float64]
TimeoutAction = Literal["stop", "halt"]
"""What the node does when commands stop arriving: ``stop`` blends to the rest pose and ends
the node in the robot's stop policy (as Ctrl-C does); ``halt`` sets speed and turn to 0 (a
joint command's last target is held) and keeps serving."""


class CommandError(SnakebotError, ValueError):
    """A command message that cannot be played (an unknown joint name, a length that does not
    match, a non-finite value); the message is dropped and the motion goes on."""


@dataclass(frozen=True)
class Steer:
    """Drive the live gait: ``speed`` and ``turn`` in -1..1, as ``snakebot drive``'s stick."""

    speed: float
    turn: float


@dataclass(frozen=True)
class JointTargets:
    """Position targets (N,) rad, head to tail; NaN for a joint the message did not name."""

    position_rad: FloatArray


@dataclass(frozen=True)
class Trajectory:
    """Waypoints played from their arrival: ``times_s`` (K,) s after it, increasing, and
    ``position_rad`` (K, N) rad, NaN for a joint the trajectory does not name."""

    times_s: FloatArray
    position_rad: FloatArray


Command = Steer | JointTargets | Trajectory


def joint_index(names: Sequence[str]) -> dict[str, int]:
    """Joint name -> index, head to tail."""
    return {name: index for index, name in enumerate(names)}


def steer_from(linear_x: float, angular_z: float) -> Steer:
    """A ``cmd_vel`` Twist's steer: both clipped to -1..1; CommandError for a non-finite one."""
    if not (math.isfinite(linear_x) and math.isfinite(angular_z)):
        raise CommandError(f"cmd_vel: expected finite numbers, got {linear_x!r}, {angular_z!r}")
    return Steer(min(max(linear_x, -1.0), 1.0), min(max(angular_z, -1.0), 1.0))


def positions_from(
    names: Sequence[str], positions: Sequence[float], index: Mapping[str, int], what: str
) -> FloatArray:
    """(N,) rad with the named joints set and NaN elsewhere; an empty ``names`` means every
    joint, head to tail. CommandError for an unknown name, a length that does not match or a
    non-finite position."""
    count = len(index)
    names = list(names) or list(index)
    if len(positions) != len(names):
        raise CommandError(f"{what}: {len(positions)} positions for {len(names)} joint names")
    out = np.full(count, np.nan)
    for name, value in zip(names, positions, strict=True):
        joint = index.get(name)
        if joint is None:
            known = ", ".join(index)
            raise CommandError(f"{what}: unknown joint {name!r} (the robot's joints: {known})")
        if not math.isfinite(value):
            raise CommandError(f"{what}: joint {name!r} position is {value!r}")
        out[joint] = value
    return out


def trajectory_from(
    names: Sequence[str],
    points: Sequence[tuple[float, Sequence[float]]],
    index: Mapping[str, int],
) -> Trajectory:
    """A Trajectory of ``(time_from_start_s, positions)`` points; CommandError for none, times
    that do not increase, or positions ``positions_from`` refuses."""
    if not points:
        raise CommandError("joint_trajectory: no points")
    times = np.array([t for t, _ in points], dtype=float)
    if not np.all(np.isfinite(times)) or times[0] < 0 or np.any(np.diff(times) <= 0):
        raise CommandError(f"joint_trajectory: time_from_start must increase from 0, got {times}")
    rows = [positions_from(names, p, index, "joint_trajectory") for _, p in points]
    return Trajectory(times, np.stack(rows))


class CommandInbox:
    """Where the ROS callbacks leave commands and the control loop takes them (thread-safe).

    Only the newest motion command counts (a steer or joint targets replace the one before, as
    a new set point does); a gait selection is kept until taken. ``last_command_s`` is when the
    newest motion command arrived (``clock`` seconds, monotonic), None before the first.
    """

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self.clock = clock
        self.received = 0
        self.refused = 0
        self.last_command_s: float | None = None
        self._lock = threading.Lock()
        self._command: Command | None = None
        self._gait: GaitChoice | None = None

    def put(self, command: Command) -> None:
        """Leave a motion command (the newest wins)."""
        with self._lock:
            self._command = command
            self.received += 1
            self.last_command_s = self.clock()

    def select(self, choice: GaitChoice) -> None:
        """Leave a gait selection (already checked to be drivable)."""
        with self._lock:
            self._gait = choice

    def refuse(self) -> None:
        """Count a message that could not be turned into a command."""
        with self._lock:
            self.refused += 1

    def take(self) -> tuple[Command | None, GaitChoice | None]:
        """The newest motion command and gait selection since the last take (None: none)."""
        with self._lock:
            command, gait = self._command, self._gait
            self._command = self._gait = None
        return command, gait


class CommandedGait(Gait):
    """The gait the node's control cycle plays: the live gait, or the joint commands.

    In ``live`` mode the targets are ``live``'s (cmd_vel steers it, phase-continuous); in
    ``joints`` mode they are the newest joint targets, or a trajectory interpolated linearly in
    time from the targets of the cycle it arrived in (a joint a command does not name keeps its
    target). Switching back to the live gait starts it from the last target, so no target jumps.
    """

    def __init__(self, live: LiveGait) -> None:
        self.live = live
        self.joint_count = live.joint_count
        self.mode: Literal["live", "joints"] = "live"
        self._last: FloatArray | None = None
        self._times = np.zeros(1)
        self._points = np.zeros((1, self.joint_count))
        self._start_s = 0.0

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """Not available: the commands depend on what ROS sends, not on time alone."""
        raise GaitError("the ROS node's gait is played cycle by cycle with command()")

    @property
    def uses_measured_pose(self) -> bool:
        """True: it starts from the measured pose and follows commands as they come."""
        return True

    @property
    def last_target_rad(self) -> FloatArray | None:
        """The last targets made (N,) rad, None before the first cycle."""
        return self._last

    def reset(self) -> None:
        """Forget the motion: the next command starts from the measured pose, live."""
        self.live.reset()
        self.mode = "live"
        self._last = None

    def follow(self, command: JointTargets | Trajectory, now_s: float) -> None:
        """Play ``command`` from gait time ``now_s`` (s); joints it leaves NaN keep the target."""
        base = self._last if self._last is not None else self.live.rest
        if isinstance(command, JointTargets):
            times, points = np.zeros(1), command.position_rad[None, :]
        else:
            times, points = command.times_s, command.position_rad
            if times[0] > 0:  # from where the joints are told to be now to the first point
                times, points = np.concatenate(([0.0], times)), np.vstack((base, points))
        self._times = times
        self._points = np.where(np.isnan(points), base, points)
        self._start_s = now_s
        self.mode = "joints"

    def go_live(self) -> None:
        """Back to the live gait, holding the last target (select a gait to move on)."""
        if self.mode == "joints":
            self.mode = "live"
            if self._last is not None:
                self.live.start(self._last)

    def command(self, time_s: float, measured_rad: FloatArray | None = None) -> FloatArray:
        """Targets (N,) rad at gait time ``time_s`` s (see the class doc)."""
        if self.mode == "live":
            pose = self.live.command(time_s, measured_rad)
        else:
            pose = self._played(time_s - self._start_s)
        self._last = pose
        return pose

    def _played(self, since_s: float) -> FloatArray:
        times, points = self._times, self._points
        if since_s >= times[-1]:
            last: FloatArray = points[-1].copy()
            return last
        after = int(np.searchsorted(times, since_s, side="right"))
        if after == 0:
            first: FloatArray = points[0].copy()
            return first
        t0, t1 = times[after - 1], times[after]
        fraction = (since_s - t0) / (t1 - t0)
        played: FloatArray = points[after - 1] + fraction * (points[after] - points[after - 1])
        return played


class CommandDriver:
    """Hands the inbox's commands to the gait once a cycle and keeps the command watchdog.

    A steer goes through ``controller`` (``snakebot drive``'s: ``speed=V``/``turn=V`` keys,
    the stick's path); a gait selection blends the live gait into it. After ``timeout_s``
    without a motion command (armed by the first; 0 switches it off) the driver does
    ``on_timeout``; a command after a halt drives again. Until the first command the joints
    hold the pose they started in (the first steer blends into the gait from there).
    ``stop_reason`` is set once the node is stopping (a timeout with ``stop``, a signal); the
    live gait then blends to rest.
    """

    def __init__(
        self,
        gait: CommandedGait,
        controller: DriveController,
        inbox: CommandInbox,
        *,
        timeout_s: float,
        on_timeout: TimeoutAction = "stop",
    ) -> None:
        if not (timeout_s >= 0 and math.isfinite(timeout_s)):
            raise ValueError(f"timeout_s must be seconds >= 0, got {timeout_s!r}")
        self.gait, self.controller, self.inbox = gait, controller, inbox
        self.timeout_s, self.on_timeout = timeout_s, on_timeout
        self.choice = controller.gaits[0]
        self.timeouts = 0
        self._halted = False
        self._steering = False  # the live gait plays a gait (a steer came since the start)

    @property
    def stop_reason(self) -> str | None:
        """Why the node is stopping, None while it serves."""
        return self.controller.stop_reason

    def apply(self, now_s: float) -> None:
        """Take the inbox's commands at gait time ``now_s`` (s) and check the watchdog."""
        if self.stop_reason is not None:
            return
        command, choice = self.inbox.take()
        live = self.gait.live
        if choice is not None:
            self.choice = choice
            if self.gait.mode == "live" and self._steering:
                live.select(choice.name, choice.params)
        if isinstance(command, Steer):
            if not self._steering:  # from the pose held, or the last joint target: no jump
                self.gait.go_live()
                live.set_controls(replace(live.setpoint, speed=0.0, turn=0.0))
                live.select(self.choice.name, self.choice.params)
                self._steering = True
            self.controller.apply(f"speed={command.speed:g}", now_s)
            self.controller.apply(f"turn={command.turn:g}", now_s)
        elif command is not None:
            self.gait.follow(command, now_s)
            self._steering = False
        if command is not None:
            self._halted = False
        self._watch(now_s)

    def stop(self, reason: str) -> None:
        """Blend to the rest pose (from the last joint target, if joints were commanded)."""
        if self.stop_reason is None:
            self.gait.go_live()
            self.controller.request_stop(reason)

    def _watch(self, now_s: float) -> None:
        last = self.inbox.last_command_s
        if self.timeout_s == 0 or last is None or self._halted:
            return
        silent_s = self.inbox.clock() - last
        if silent_s <= self.timeout_s:
            return
        self.timeouts += 1
        if self.on_timeout == "stop":
            self.stop(f"no command for {self.timeout_s:g} s")
        else:
            self._halted = True
            self.controller.apply("x", now_s)  # halt: speed and turn to 0; joints hold
