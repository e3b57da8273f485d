"""Go to a point: a heading controller that steers a gait toward (x, y), on any pose source.

``GoToPoint`` wraps a lateral-undulation gait (travel along the body's axis: ``serpenoid``,
``lateral_undulation``) and adds a turning offset to its yaw joints, proportional to the angle
between where the snake heads (its virtual chassis's x axis, from the pose source) and where
the point is, clipped and slew-limited. The pose source is the odometry on the servos
(``ChassisOdometry``) or anything with ``body_state()``; ``reached`` is the run's stop check.
``snakebot run --to X,Y`` is this on the robot's gait.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np
import numpy.typing as npt

from snakebot.gaits import Gait
from snakebot.types import BodyState

if TYPE_CHECKING:
    from snakebot.estimation.odometry import ChassisOdometry

FloatArray = npt.NDArray[np.float64]

SPEED_WINDOW_S = 2.0
"""The estimated speed is the straight-line way over this much of the latest time (a gait
cycle or more, so the wave's sway averages out)."""

STEERABLE_GAITS = ("serpenoid", "lateral_undulation")
"""Gaits that travel along the body's axis and turn with a yaw offset."""


class HeadingSource(Protocol):
    """Where the snake is and heads: ``body_state()`` for the goal's frame at the start and the
    distance to it, ``pose`` for the chassis heading (``ChassisOdometry`` is one)."""

    def body_state(self) -> BodyState | None:
        """The body now, or None before the first cycle."""
        ...


@dataclass(frozen=True)
class SteeringConfig:
    """The heading controller: ``gain`` rad of yaw offset per rad of heading error, at most
    ``max_offset_rad``, changing at most ``offset_rate_rad_s``. ``tolerance_m``: how near the
    point counts as there, plus the way the snake still goes at its present speed for
    ``coast_s`` (the ramp-out after the stop: half its length for a smooth ramp).
    ``offset_sign``: the gait's sense (+1: a positive offset turns the snake counter-clockwise;
    the serpenoid's turns it clockwise, -1). ValueError for a value out of range."""

    gain: float = 0.3
    max_offset_rad: float = 0.12
    offset_rate_rad_s: float = 0.3
    tolerance_m: float = 0.1
    offset_sign: float = -1.0
    coast_s: float = 0.0

    def __post_init__(self) -> None:
        if not (self.coast_s >= 0 and math.isfinite(self.coast_s)):
            raise ValueError(f"coast_s must be >= 0, got {self.coast_s!r}")
        for name in ("gain", "max_offset_rad", "offset_rate_rad_s", "tolerance_m"):
            value = getattr(self, name)
            if not (value > 0 and math.isfinite(value)):
                raise ValueError(f"{name} must be a positive number, got {value!r}")
        if self.offset_sign not in (-1.0, 1.0):
            raise ValueError(f"offset_sign must be +1 or -1, got {self.offset_sign!r}")


class GoToPoint(Gait):
    """``gait`` steered toward ``point_m`` (x ahead, y left, m from the centre of mass at the
    first cycle, in the head's frame then) by ``odometry``'s pose; ``yaw_mask`` (N,) bool marks
    the joints the turning offset goes on. ``reached()`` is a stop check."""

    def __init__(
        self,
        gait: Gait,
        odometry: ChassisOdometry,
        point_m: tuple[float, float],
        yaw_mask: npt.ArrayLike,
        config: SteeringConfig | None = None,
    ) -> None:
        self.gait = gait
        self.joint_count = gait.joint_count
        self.odometry = odometry
        self.point_m = (float(point_m[0]), float(point_m[1]))
        if not all(math.isfinite(v) for v in self.point_m):
            raise ValueError(f"the point must be two finite numbers, got {point_m}")
        self.yaw_mask = np.asarray(yaw_mask, dtype=bool)
        if self.yaw_mask.shape != (self.joint_count,):
            raise ValueError(f"yaw_mask must have shape ({self.joint_count},)")
        self.config = config if config is not None else SteeringConfig()
        self.goal_m: FloatArray | None = None
        self.offset_rad = 0.0
        self.speed_mps = 0.0
        self._last_time_s: float | None = None
        self._track: deque[tuple[float, float, float]] = deque()

    @property
    def period_s(self) -> float | None:
        """The steered gait's period."""
        return self.gait.period_s

    @property
    def uses_measured_pose(self) -> bool:
        """Closed loop: it steers on the pose estimate."""
        return True

    def reset(self) -> None:
        """Start afresh: no goal yet (set at the first pose), no offset."""
        self.gait.reset()
        self.goal_m = None
        self.offset_rad = 0.0
        self.speed_mps = 0.0
        self._last_time_s = None
        self._track.clear()

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """The gait's targets with the current offset (the offset changes only in command)."""
        return self.gait.targets(time_s) + self.offset_rad * self.yaw_mask

    def distance_m(self) -> float | None:
        """How far the estimated centre of mass is from the point, or None before a pose."""
        body = self.odometry.body_state()
        if body is None or self.goal_m is None:
            return None
        return float(np.hypot(*(self.goal_m - body.com_m[:2])))

    def reached(self) -> str | None:
        """A stop check: a reason once the estimate is within the tolerance of the point."""
        distance = self.distance_m()
        coast = self.config.coast_s * self.speed_mps
        if distance is not None and distance <= self.config.tolerance_m + coast:
            return f"reached the point (estimated {distance:.2f} m from it)"
        return None

    def command(self, time_s: float, measured_rad: FloatArray | None = None) -> FloatArray:
        """The gait's command plus the steering offset on the yaw joints, rad (N,)."""
        self._steer(time_s)
        base = self.gait.command(time_s, measured_rad)
        out: FloatArray = base + self.offset_rad * self.yaw_mask
        return out

    def _steer(self, time_s: float) -> None:
        body = self.odometry.body_state()
        pose = self.odometry.pose
        dt = 0.0 if self._last_time_s is None else max(time_s - self._last_time_s, 0.0)
        self._last_time_s = time_s
        if body is None or pose is None:
            return
        track = self._track
        track.append((pose.time_s, pose.x_m, pose.y_m))
        while track[-1][0] - track[0][0] > SPEED_WINDOW_S:
            track.popleft()
        span = track[-1][0] - track[0][0]
        if span > 0.5 * SPEED_WINDOW_S:
            moved = math.hypot(track[-1][1] - track[0][1], track[-1][2] - track[0][2])
            self.speed_mps = moved / span
        if self.goal_m is None:
            yaw = head_heading_rad(body.head_quat)
            x, y = self.point_m
            c, s = math.cos(yaw), math.sin(yaw)
            self.goal_m = body.com_m[:2] + np.array([c * x - s * y, s * x + c * y])
        to_goal = self.goal_m - body.com_m[:2]
        bearing = math.atan2(float(to_goal[1]), float(to_goal[0]))
        error = math.remainder(bearing - pose.yaw_rad, 2 * math.pi)
        config = self.config
        wanted = config.offset_sign * config.gain * error
        wanted = min(max(wanted, -config.max_offset_rad), config.max_offset_rad)
        step = config.offset_rate_rad_s * dt
        self.offset_rad += min(max(wanted - self.offset_rad, -step), step)


def head_heading_rad(quat: npt.ArrayLike) -> float:
    """Heading of the head's x axis in the horizontal plane for its orientation (w, x, y, z)."""
    w, x, y, z = (float(v) for v in np.asarray(quat, dtype=float))
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
