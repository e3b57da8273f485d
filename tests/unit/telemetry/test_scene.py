"""The 3-D scene: forward kinematics of measured joints through the twin's model."""

from __future__ import annotations

import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.telemetry.scene import KinematicLinkPoses, frame_transforms, scene_update
from snakebot.types import JointCommand


def test_straight_joints_lay_the_links_head_to_tail_along_minus_x() -> None:
    robot = load_robot("snake8")
    xpos, xquat = KinematicLinkPoses(robot).poses(np.zeros(robot.joint_count))
    assert xpos.shape == (robot.link_count, 3)
    assert np.allclose(xpos[:, 0], -robot.link.length_m * np.arange(robot.link_count))
    assert np.allclose(xpos[:, 1], 0.0)
    assert np.allclose(xquat, [1.0, 0.0, 0.0, 0.0])


def test_fk_of_the_twins_measured_joints_reproduces_the_twins_shape() -> None:
    robot = load_robot("snake12")  # yaw and pitch joints
    fk = KinematicLinkPoses(robot)
    with TwinBackend(robot) as twin:
        command = 0.4 * np.sin(np.arange(robot.joint_count))
        for _ in range(60):
            twin.send_command(JointCommand(command))
            twin.advance(0.01)
        measured = twin.read_state().position_rad
        # mj_step leaves xpos at the state before its last integration: recompute for this qpos.
        mujoco.mj_kinematics(twin.model, twin.data)
        ids = [twin.model.body(f"link{i}").id for i in range(robot.link_count)]
        twin_pos, twin_quat = twin.data.xpos[ids].copy(), twin.data.xquat[ids].copy()
    assert np.abs(measured).max() > 0.2  # the snake is bent, not straight
    fk_pos, fk_quat = fk.poses(measured)

    def in_head_frame(pos: np.ndarray, quat: np.ndarray) -> np.ndarray:
        head = Rotation.from_quat(quat[0], scalar_first=True)
        return head.inv().apply(pos - pos[0])

    assert np.allclose(
        in_head_frame(fk_pos, fk_quat), in_head_frame(twin_pos, twin_quat), atol=1e-9
    )


def test_messages_name_every_link_frame_and_draw_a_capsule_per_link() -> None:
    robot = load_robot("snake8")
    xpos, xquat = KinematicLinkPoses(robot).poses(np.full(robot.joint_count, 0.3))
    message = frame_transforms(1_500_000_000, xpos, xquat)
    first = message["transforms"][1]
    assert first["timestamp"] == {"sec": 1, "nsec": 500_000_000}
    assert (first["parent_frame_id"], first["child_frame_id"]) == ("world", "link1")
    assert first["rotation"]["w"] == round(float(xquat[1, 0]), 6)
    scene = scene_update(0, robot.link_count, robot.link.length_m, robot.link.radius_m)
    entity = scene["entities"][2]
    assert entity["frame_id"] == "link2" and entity["frame_locked"]
    cylinder = entity["cylinders"][0]
    assert cylinder["size"]["z"] == robot.link.length_m - 2 * robot.link.radius_m
    assert [s["pose"]["position"]["x"] for s in entity["spheres"]] == [
        -robot.link.radius_m,
        -(robot.link.length_m - robot.link.radius_m),
    ]
