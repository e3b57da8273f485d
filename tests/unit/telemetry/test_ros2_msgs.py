"""The ROS 2 message definitions and builders of a recording, against ROS 2 Kilted's own types."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from snakebot.telemetry import ros2_msgs


def test_every_definition_is_the_kilted_type_field_for_field() -> None:
    typesys = pytest.importorskip("rosbags.typesys")
    kilted = typesys.get_typestore(typesys.Stores.ROS2_KILTED)
    for name, text in ros2_msgs.DEFINITIONS.items():
        parsed = typesys.get_types_from_msg(text, name)
        assert name in parsed
        for type_name, fields in parsed.items():
            assert fields == kilted.fielddefs[type_name], type_name
    assert set(ros2_msgs.TOPIC_TYPES.values()) == set(ros2_msgs.DEFINITIONS)


def test_a_stamp_splits_nanoseconds_into_seconds_and_nanoseconds() -> None:
    stamp = ros2_msgs.header(1_796_225_600_999_999_999, "world")
    assert stamp == {"stamp": {"sec": 1_796_225_600, "nanosec": 999_999_999}, "frame_id": "world"}


def test_a_transform_writes_mujocos_wxyz_quaternion_in_ros_order() -> None:
    message = ros2_msgs.transform_stamped(
        5, "world", "link0", np.array([1.0, 2.0, 3.0]), np.array([0.5, 0.1, 0.2, 0.3])
    )
    assert message["transform"]["rotation"] == {"x": 0.1, "y": 0.2, "z": 0.3, "w": 0.5}
    assert message["transform"]["translation"] == {"x": 1.0, "y": 2.0, "z": 3.0}
    assert message["child_frame_id"] == "link0"
    tf = ros2_msgs.tf_message(5, "world", ["a", "b"], np.eye(2, 3), np.eye(2, 4))
    assert [t["child_frame_id"] for t in tf["transforms"]] == ["a", "b"]
    assert tf["transforms"][1]["transform"]["rotation"]["x"] == 1.0


def test_a_joint_state_sends_what_is_not_measured_empty() -> None:
    message = ros2_msgs.joint_state(0, ["joint0"], np.array([0.25]))
    assert (message["position"], message["velocity"], message["effort"]) == ([0.25], [], [])


def test_diagnostic_values_are_strings() -> None:
    status = ros2_msgs.diagnostic_status("n", ros2_msgs.OK, "OK", {"a": 1 / 3, "b": None, "c": 7})
    assert status["values"] == [
        {"key": "a", "value": "0.333333"},
        {"key": "b", "value": ""},
        {"key": "c", "value": "7"},
    ]


@pytest.mark.skipif(
    importlib.util.find_spec("snakebot.ros2") is None, reason="snakebot ros2 is not in this tree"
)
def test_the_recording_uses_the_live_nodes_topics_types_and_frames() -> None:
    from snakebot.ros2 import topics

    for topic in (topics.JOINT_STATES, topics.DIAGNOSTICS, topics.RUN_METRICS, topics.BODY_POSE):
        assert ros2_msgs.TOPIC_TYPES["/" + topic.name] == topic.type
    assert (ros2_msgs.WORLD_FRAME, ros2_msgs.BODY_FRAME) == (topics.WORLD_FRAME, topics.BODY_FRAME)
    subscribed = {"/" + t.name for t in topics.TOPICS if t.direction == "subscribe"}
    assert not subscribed & set(ros2_msgs.TOPIC_TYPES)  # a replayed bag commands no robot
