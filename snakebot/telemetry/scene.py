"""The snake in 3-D for Foxglove: link poses (twin or forward kinematics) and their messages.

On the twin the link poses are the simulated bodies'. On hardware they are the forward
kinematics of the measured joint angles through the twin's own ``MjModel`` (the same link
lengths, axes and joint order), with the head held at the origin: a real run and its twin are
drawn by the same scene, frame for frame. Frames are ``world`` -> ``link0`` (head) ...
``link<N>`` (tail); each link is drawn as a capsule (a cylinder and two spheres) locked to its
frame.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import mujoco
import numpy as np

from snakebot.backends.twin.model_builder import build_model, joint_name, link_name
from snakebot.config.schema import RobotConfig

WORLD_FRAME = "world"
HEAD_RGBA = (0.85, 0.45, 0.1, 1.0)
LINK_RGBA = (0.25, 0.25, 0.28, 1.0)


class LinkPoses(Protocol):
    """Where every link is: positions (L, 3) in m and orientations (L, 4) as (w, x, y, z)."""

    def poses(self, position_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Link poses now; ``position_rad`` (N,) are the measured joint angles."""
        ...


class TwinLinkPoses:
    """The twin's simulated link poses (its MjData after the last step); joint angles unused."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, link_count: int) -> None:
        self._data = data
        self._ids = np.array([model.body(link_name(i)).id for i in range(link_count)])

    def poses(self, position_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Copies of ``xpos`` and ``xquat`` of the links."""
        return self._data.xpos[self._ids].copy(), self._data.xquat[self._ids].copy()


class KinematicLinkPoses:
    """Forward kinematics of measured joint angles through the twin's model of ``robot``.

    The head stays where the twin starts it (at the origin, facing +x); ``mj_kinematics`` places
    the other links. Costs a few microseconds per call for a dozen links.
    """

    def __init__(self, robot: RobotConfig) -> None:
        self._model, _ = build_model(robot)
        self._data = mujoco.MjData(self._model)
        joints = [self._model.joint(joint_name(i)).id for i in range(robot.joint_count)]
        self._qpos_index = np.array([self._model.jnt_qposadr[j] for j in joints])
        self._ids = np.array([self._model.body(link_name(i)).id for i in range(robot.link_count)])

    def poses(self, position_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Link poses for joint angles ``position_rad`` (N,) rad."""
        self._data.qpos[self._qpos_index] = position_rad
        mujoco.mj_kinematics(self._model, self._data)
        return self._data.xpos[self._ids].copy(), self._data.xquat[self._ids].copy()


def stamp(time_ns: int) -> dict[str, int]:
    """A Foxglove JSON time: whole seconds and nanoseconds."""
    sec, nsec = divmod(int(time_ns), 1_000_000_000)
    return {"sec": sec, "nsec": nsec}


def frame_transforms(
    time_ns: int, positions_m: np.ndarray, quats_wxyz: np.ndarray
) -> dict[str, Any]:
    """A ``foxglove.FrameTransforms`` message: ``world`` -> ``link<i>`` for every link."""
    when = stamp(time_ns)
    transforms = []
    positions, quats = np.round(positions_m, 6).tolist(), np.round(quats_wxyz, 6).tolist()
    for index, (p, q) in enumerate(zip(positions, quats, strict=True)):
        transforms.append(
            {
                "timestamp": when,
                "parent_frame_id": WORLD_FRAME,
                "child_frame_id": link_name(index),
                "translation": {"x": p[0], "y": p[1], "z": p[2]},
                "rotation": {"x": q[1], "y": q[2], "z": q[3], "w": q[0]},
            }
        )
    return {"transforms": transforms}


def scene_update(time_ns: int, link_count: int, length_m: float, radius_m: float) -> dict[str, Any]:
    """A ``foxglove.SceneUpdate``: one capsule per link, locked to its frame, kept until replaced.

    A capsule spans ``-radius`` to ``-(length - radius)`` along the link's x axis, as in the twin.
    """
    half = math.sqrt(0.5)
    along_x = {"x": 0.0, "y": half, "z": 0.0, "w": half}  # a cylinder's axis is its z
    straight = max(length_m - 2 * radius_m, 0.0)
    diameter = 2 * radius_m
    entities = []
    for index in range(link_count):
        r, g, b, a = HEAD_RGBA if index == 0 else LINK_RGBA
        color = {"r": r, "g": g, "b": b, "a": a}

        def at(x: float) -> dict[str, Any]:
            return {"position": {"x": x, "y": 0.0, "z": 0.0}, "orientation": along_x}

        ends = (-radius_m, -(length_m - radius_m))
        entities.append(
            {
                "timestamp": stamp(time_ns),
                "frame_id": link_name(index),
                "id": link_name(index),
                "lifetime": {"sec": 0, "nsec": 0},
                "frame_locked": True,
                "cylinders": [
                    {
                        "pose": at(-length_m / 2),
                        "size": {"x": diameter, "y": diameter, "z": straight},
                        "bottom_scale": 1.0,
                        "top_scale": 1.0,
                        "color": color,
                    }
                ],
                "spheres": [
                    {
                        "pose": at(x),
                        "size": {"x": diameter, "y": diameter, "z": diameter},
                        "color": color,
                    }
                    for x in ends
                ],
            }
        )
    return {"deletions": [], "entities": entities}
