"""Start the snake wrapped on the pole terrain's pole, as CMU's robots are wrapped by hand.

A pole-climbing gait (the rolling helix) climbs from a coil around the pole; lying beside the
pole, the same gait only coils the body on the ground (docs/twin.md). :func:`wrap_on_pole` puts
the twin's body in a given joint pose (the gait's t = 0 shape), turns the coil's axis upright
onto the pole's axis, head end up, and lifts it so its lowest module is ``clearance_m`` off the
floor.
"""

from __future__ import annotations

import mujoco
import numpy as np

from snakebot.backends.twin.backend import TwinBackend
from snakebot.backends.twin.model_builder import link_name
from snakebot.errors import ConfigError

POLE_GEOM = "pole"


def _circle_across(centres: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, float, float]:
    """The least-squares circle of ``centres`` (M, 3) projected across unit ``axis`` (3,): its
    centre (3,), radius (m) and the RMS spread (m) of the points' distances from it."""
    u = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    x, y = centres @ u, centres @ v
    (d, e, _), *_ = np.linalg.lstsq(np.column_stack([x, y, np.ones_like(x)]), -(x * x + y * y))
    cx, cy = -d / 2, -e / 2
    radial = np.hypot(x - cx, y - cy)
    return cx * u + cy * v, float(radial.mean()), float(radial.std())


def helix_axis(centres: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """The axis of the coil through module centres ``centres`` (M, 3), m, head first: (unit
    axis (3,) pointing to the head's end, a point on it (3,) m, radius m).

    The axis the modules' second differences (their turns) are most nearly normal to, then
    tilted by a pattern search to make the modules' distances from it as equal as it can.
    """
    _, _, vt = np.linalg.svd(np.diff(centres, 2, axis=0))
    axis = vt[2]
    spread = _circle_across(centres, axis)[2]
    step = 0.2
    while step > 1e-4:
        across = np.linalg.svd(axis[None, :])[2][1:]
        trials = [axis + sign * step * w for w in across for sign in (1.0, -1.0)]
        best = min(trials, key=lambda a: _circle_across(centres, a / np.linalg.norm(a))[2])
        best /= np.linalg.norm(best)
        best_spread = _circle_across(centres, best)[2]
        if best_spread < spread:
            axis, spread = best, best_spread
        else:
            step /= 2
    point, radius, _ = _circle_across(centres, axis)
    if np.dot(centres[0] - centres[-1], axis) < 0:
        axis = -axis
    return axis, point, radius


def wrap_on_pole(twin: TwinBackend, pose_rad: np.ndarray, *, clearance_m: float = 0.005) -> None:
    """Reset ``twin`` to joint pose ``pose_rad`` (N,) rad, coiled around the terrain's pole.

    The coil's axis (:func:`helix_axis` of the module centres) is set on the pole's axis,
    pointing up (head end up), the lowest module's surface ``clearance_m`` m above the floor, at
    rest. ConfigError if the twin's terrain has no pole (``--terrain pole``); ValueError for a
    wrong shape of ``pose_rad``.
    """
    model, data = twin.model, twin.data
    try:
        pole = np.array(model.geom(POLE_GEOM).pos, dtype=float)
    except KeyError:
        raise ConfigError(
            "terrain", "pole", "a start wrapped on the pole needs the pole terrain"
        ) from None
    twin.reset(np.asarray(pose_rad, dtype=float))
    ids = [model.geom(f"{link_name(i)}_geom").id for i in range(twin.robot.link_count)]
    centres = np.array(data.geom_xpos[ids], dtype=float)
    axis, point, _ = helix_axis(centres)
    x = np.cross([0.0, 1.0, 0.0], axis)
    x /= np.linalg.norm(x)
    turn = np.stack([x, np.cross(axis, x), axis])  # rows: the new world axes in today's frame
    lowest = float(((centres - point) @ turn.T)[:, 2].min())
    target = np.array([pole[0], pole[1], twin.robot.link.radius_m + clearance_m - lowest])
    head_pos = np.array(data.qpos[:3], dtype=float)
    head_rot = np.zeros(9)
    mujoco.mju_quat2Mat(head_rot, data.qpos[3:7])
    data.qpos[:3] = turn @ (head_pos - point) + target
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, (turn @ head_rot.reshape(3, 3)).flatten())
    data.qpos[3:7] = quat
    data.qvel[:] = 0.0
    mujoco.mj_forward(model, data)
