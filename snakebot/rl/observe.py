"""Observations, built the same way in the environments and when a policy plays as a gait.

Numpy only: a policy on a real snake builds its observation from what the servos report
(``JointState``), the gait phases, and the command or goal. Every entry is scaled to about
[-1, 1] and clipped to +-``OBS_BOUND``.
"""

from __future__ import annotations

import numpy as np

from snakebot.control.metrics import head_yaw_rad
from snakebot.gaits.base import FloatArray
from snakebot.types import BodyState, JointState

OBS_BOUND = 10.0


def joint_features(
    state: JointState, lower_rad: FloatArray, upper_rad: FloatArray, max_speed_rad_s: float
) -> FloatArray:
    """Angles as a fraction of their limit, velocities per servo speed limit: shape (2N,)."""
    limit = np.where(state.position_rad >= 0.0, upper_rad, -lower_rad)
    angles = state.position_rad / np.maximum(limit, 1e-6)
    return np.concatenate([angles, state.velocity_rad_s / max_speed_rad_s])


def goal_in_head_frame(body: BodyState, goal_xy_m: FloatArray, body_length_m: float) -> FloatArray:
    """The goal as seen from the centre of mass, in the head's heading frame, in body lengths:
    shape (2,), x forward (the head's +x), y to the left."""
    dx, dy = (np.asarray(goal_xy_m, dtype=np.float64) - body.com_m[:2]).tolist()
    yaw = head_yaw_rad(body.head_quat)
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([c * dx + s * dy, -s * dx + c * dy]) / body_length_m


def goal_observation(
    state: JointState,
    body: BodyState,
    goal_xy_m: FloatArray,
    phases: FloatArray,
    limits: tuple[FloatArray, FloatArray],
    max_speed_rad_s: float,
    body_length_m: float,
) -> np.ndarray:
    """SnakeGoal's observation, float32: joints (2N), phases (sin, cos) (2P), goal (2)."""
    parts = (
        joint_features(state, *limits, max_speed_rad_s),
        phases,
        goal_in_head_frame(body, goal_xy_m, body_length_m),
    )
    return _finish(parts)


def velocity_observation(
    state: JointState,
    phases: FloatArray,
    command: FloatArray,
    limits: tuple[FloatArray, FloatArray],
    max_speed_rad_s: float,
    stall_torque_nm: float,
    command_scale: FloatArray,
) -> np.ndarray:
    """SnakeVelocity's observation, float32: joints (2N), efforts per stall torque (N), phases
    (2P), command (speed m/s, turn rate rad/s) divided by ``command_scale`` (2)."""
    parts = (
        joint_features(state, *limits, max_speed_rad_s),
        state.effort_nm / stall_torque_nm,
        phases,
        np.asarray(command, dtype=np.float64) / command_scale,
    )
    return _finish(parts)


def _finish(parts: tuple[FloatArray, ...]) -> np.ndarray:
    out = np.concatenate(parts).astype(np.float32)
    np.clip(out, -OBS_BOUND, OBS_BOUND, out=out)
    return out
