"""The ROS 2 message definitions and builders of a recording, against ROS 2 Kilted's own types."""

from __future__ import annotations

import importlib.util
import io
from typing import Any

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


def reference_cdr(kind: str, message: dict[str, Any]) -> bytes:
    """``message`` encoded by mcap-ros2-support's own (dynamic) encoder from the definition."""
    mcap_ros2_writer = pytest.importorskip("mcap_ros2.writer")
    from mcap.reader import make_reader

    stream = io.BytesIO()
    writer = mcap_ros2_writer.Writer(stream)
    schema = writer.register_msgdef(kind, ros2_msgs.DEFINITIONS[kind])
    writer.write_message("/t", schema, message, log_time=0)
    writer.finish()
    stream.seek(0)
    return bytes(next(iter(make_reader(stream).iter_messages()))[2].data)


def kilted(kind: str, data: bytes) -> Any:
    typesys = pytest.importorskip("rosbags.typesys")
    return typesys.get_typestore(typesys.Stores.ROS2_KILTED).deserialize_cdr(data, kind)


def stamp(time_ns: int, frame_id: str = "") -> dict[str, Any]:
    sec, nanosec = divmod(time_ns, 1_000_000_000)
    return {"stamp": {"sec": sec, "nanosec": nanosec}, "frame_id": frame_id}


WHEN = 1_796_225_600_999_999_999


@pytest.mark.parametrize("joints", [1, 2, 3, 12])
def test_joint_states_are_the_reference_encoders_bytes(joints: int) -> None:
    names = [f"joint{i}" for i in range(joints)]
    rng = np.random.default_rng(joints)
    q, qd, tau = rng.normal(size=(3, joints))
    measured = ros2_msgs.JointStates(names)(WHEN, q, qd, tau)
    expected = {"header": stamp(WHEN), "name": names}
    expected |= {"position": q.tolist(), "velocity": qd.tolist(), "effort": tau.tolist()}
    assert measured == reference_cdr(ros2_msgs.JOINT_STATE, expected)
    sent = ros2_msgs.JointStates(names, measured=False)(WHEN, q)
    expected |= {"velocity": [], "effort": []}
    assert sent == reference_cdr(ros2_msgs.JOINT_STATE, expected)
    decoded = kilted(ros2_msgs.JOINT_STATE, measured)
    assert decoded.name == names and np.array_equal(decoded.effort, tau)
    assert (decoded.header.stamp.sec, decoded.header.stamp.nanosec) == (1_796_225_600, 999_999_999)


def test_joint_states_refuse_arrays_of_another_length() -> None:
    encode = ros2_msgs.JointStates(["joint0", "joint1"])
    with pytest.raises(ValueError, match="3 values for 2 joints"):
        encode(0, np.zeros(3), np.zeros(3), np.zeros(3))
    with pytest.raises(ValueError, match="velocities and efforts"):
        encode(0, np.zeros(2))


def test_transforms_write_mujocos_wxyz_quaternion_in_ros_order() -> None:
    children = ["link0", "a_longer_link_name", "l2"]
    positions = np.arange(9.0).reshape(3, 3)
    quats = np.array([[0.5, 0.1, 0.2, 0.3], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])
    data = ros2_msgs.Transforms("world", children)(WHEN, positions, quats)
    transforms = [
        {
            "header": stamp(WHEN, "world"),
            "child_frame_id": child,
            "transform": {
                "translation": dict(zip("xyz", p.tolist(), strict=True)),
                "rotation": {"x": q[1], "y": q[2], "z": q[3], "w": q[0]},
            },
        }
        for child, p, q in zip(children, positions, quats, strict=True)
    ]
    assert data == reference_cdr(ros2_msgs.TF_MESSAGE, {"transforms": transforms})
    first = kilted(ros2_msgs.TF_MESSAGE, data).transforms[0]
    rotation = first.transform.rotation
    assert (rotation.x, rotation.y, rotation.z, rotation.w) == (0.1, 0.2, 0.3, 0.5)
    single = ros2_msgs.Transforms("world", ["snakebot_body"], single=True)
    body = single(WHEN, np.array([1.0, 2.0, 3.0]), np.array([0.5, 0.1, 0.2, 0.3]))
    expected = dict(transforms[0], child_frame_id="snakebot_body")
    expected["transform"] = {**expected["transform"], "translation": {"x": 1.0, "y": 2.0, "z": 3.0}}
    assert body == reference_cdr(ros2_msgs.TRANSFORM_STAMPED, expected)
    with pytest.raises(ValueError, match="one child"):
        ros2_msgs.Transforms("world", ["a", "b"], single=True)


def test_diagnostics_are_the_reference_encoders_bytes() -> None:
    servo = ros2_msgs.diagnostic_status(
        "snakebot: joint0", ros2_msgs.ERROR, "overload", {"a": 1 / 3, "b": None}, "servo 1"
    )
    run = ros2_msgs.diagnostic_status("snakebot: run", ros2_msgs.OK, "OK", {"cycles": 7})
    assert servo.values == (("a", "0.333333"), ("b", ""))
    assert run.values == (("cycles", "7"),)

    def as_dict(status: ros2_msgs.Status) -> dict[str, Any]:
        values = [{"key": k, "value": v} for k, v in status.values]
        return {
            "level": status.level,
            "name": status.name,
            "message": status.message,
            "hardware_id": status.hardware_id,
            "values": values,
        }

    array = ros2_msgs.diagnostic_array(WHEN, [servo, run])
    expected = {"header": stamp(WHEN), "status": [as_dict(servo), as_dict(run)]}
    assert array == reference_cdr(ros2_msgs.DIAGNOSTIC_ARRAY, expected)
    alone = ros2_msgs.diagnostic_status_message(run)
    assert alone == reference_cdr(ros2_msgs.DIAGNOSTIC_STATUS, as_dict(run))
    assert kilted(ros2_msgs.DIAGNOSTIC_ARRAY, array).status[0].level == ros2_msgs.ERROR


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
