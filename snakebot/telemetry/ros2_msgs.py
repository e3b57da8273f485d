"""The ROS 2 messages a snakebot recording carries: their definitions, topics and contents.

Pure data, no ROS import: each message is built as the plain dict an MCAP ``ros2msg`` writer
encodes to CDR, and each definition is the ``.msg`` text of the standard type with its
dependencies appended the way rosbag2 stores them (a line of 80 ``=``, then ``MSG: pkg/Type``),
so rosbag2, Foxglove and rosbags decode the file with no snakebot installed. The fields and
their order are those of the ROS 2 Kilted messages (sensor_msgs, diagnostic_msgs, tf2_msgs,
geometry_msgs, std_msgs, builtin_interfaces); the tests decode what is written against the
type store of a ROS installation's definitions (rosbags), not only against this text.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

JOINT_STATES_TOPIC = "/joint_states"
"""sensor_msgs/msg/JointState: what every joint measured, every cycle."""
COMMAND_TOPIC = "/snakebot/joint_commands_sent"
"""sensor_msgs/msg/JointState: the positions the safety layer sent, every cycle (not a topic
anything subscribes to: replaying a recording must not command a robot)."""
TF_TOPIC = "/tf"
"""tf2_msgs/msg/TFMessage: ``world`` -> ``link0`` (head) ... ``link<N>`` (tail)."""
DIAGNOSTICS_TOPIC = "/diagnostics"
"""diagnostic_msgs/msg/DiagnosticArray: one status per servo (health, hardware errors), then the
run's."""
RUN_METRICS_TOPIC = "/run_metrics"
"""diagnostic_msgs/msg/DiagnosticStatus: the run's status alone."""
BODY_POSE_TOPIC = "/body_pose"
"""geometry_msgs/msg/TransformStamped: ``world`` -> ``snakebot_body`` (the centre of mass, the
head's orientation) every cycle, where the backend senses the body (the twin)."""
WORLD_FRAME = "world"
BODY_FRAME = "snakebot_body"

JOINT_STATE = "sensor_msgs/msg/JointState"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
TRANSFORM_STAMPED = "geometry_msgs/msg/TransformStamped"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
DIAGNOSTIC_STATUS = "diagnostic_msgs/msg/DiagnosticStatus"

OK, WARN, ERROR, STALE = 0, 1, 2, 3
"""diagnostic_msgs/DiagnosticStatus levels."""

_SEPARATOR = "=" * 80

_TIME = "int32 sec\nuint32 nanosec\n"
_HEADER = "builtin_interfaces/Time stamp\nstring frame_id\n"
_VECTOR3 = "float64 x\nfloat64 y\nfloat64 z\n"
_QUATERNION = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"
_TRANSFORM = "Vector3 translation\nQuaternion rotation\n"
_TRANSFORM_STAMPED = "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"
_KEY_VALUE = "string key\nstring value\n"
_DIAGNOSTIC_STATUS = (
    "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\n"
    "byte level\nstring name\nstring message\nstring hardware_id\nKeyValue[] values\n"
)


def _definition(text: str, *dependencies: tuple[str, str]) -> str:
    parts = [text]
    for name, body in dependencies:
        parts.append(f"{_SEPARATOR}\nMSG: {name}\n{body}")
    return "\n".join(parts)


DEFINITIONS: dict[str, str] = {
    JOINT_STATE: _definition(
        "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n"
        "float64[] effort\n",
        ("std_msgs/Header", _HEADER),
        ("builtin_interfaces/Time", _TIME),
    ),
    TF_MESSAGE: _definition(
        "geometry_msgs/TransformStamped[] transforms\n",
        ("geometry_msgs/TransformStamped", _TRANSFORM_STAMPED),
        ("std_msgs/Header", _HEADER),
        ("builtin_interfaces/Time", _TIME),
        ("geometry_msgs/Transform", _TRANSFORM),
        ("geometry_msgs/Vector3", _VECTOR3),
        ("geometry_msgs/Quaternion", _QUATERNION),
    ),
    TRANSFORM_STAMPED: _definition(
        _TRANSFORM_STAMPED,
        ("std_msgs/Header", _HEADER),
        ("builtin_interfaces/Time", _TIME),
        ("geometry_msgs/Transform", _TRANSFORM),
        ("geometry_msgs/Vector3", _VECTOR3),
        ("geometry_msgs/Quaternion", _QUATERNION),
    ),
    DIAGNOSTIC_ARRAY: _definition(
        "std_msgs/Header header\nDiagnosticStatus[] status\n",
        ("std_msgs/Header", _HEADER),
        ("builtin_interfaces/Time", _TIME),
        ("diagnostic_msgs/DiagnosticStatus", _DIAGNOSTIC_STATUS),
        ("diagnostic_msgs/KeyValue", _KEY_VALUE),
    ),
    DIAGNOSTIC_STATUS: _definition(_DIAGNOSTIC_STATUS, ("diagnostic_msgs/KeyValue", _KEY_VALUE)),
}
"""ROS 2 type name -> its message definition (``ros2msg`` schema text)."""

TOPIC_TYPES: dict[str, str] = {
    JOINT_STATES_TOPIC: JOINT_STATE,
    COMMAND_TOPIC: JOINT_STATE,
    TF_TOPIC: TF_MESSAGE,
    BODY_POSE_TOPIC: TRANSFORM_STAMPED,
    DIAGNOSTICS_TOPIC: DIAGNOSTIC_ARRAY,
    RUN_METRICS_TOPIC: DIAGNOSTIC_STATUS,
}
"""Topic -> ROS 2 type name."""


def header(time_ns: int, frame_id: str = "") -> dict[str, Any]:
    """A std_msgs/Header stamped ``time_ns`` (ns since the Unix epoch)."""
    sec, nanosec = divmod(int(time_ns), 1_000_000_000)
    return {"stamp": {"sec": sec, "nanosec": nanosec}, "frame_id": frame_id}


def joint_state(
    time_ns: int,
    names: Sequence[str],
    position_rad: np.ndarray,
    velocity_rad_s: np.ndarray | None = None,
    effort_nm: np.ndarray | None = None,
) -> dict[str, Any]:
    """A sensor_msgs/JointState: ``names`` head to tail with their (N,) positions (rad) and,
    where given, velocities (rad/s) and efforts (N m); a missing array is sent empty, as ROS
    does for a quantity that is not measured."""
    return {
        "header": header(time_ns),
        "name": list(names),
        "position": np.asarray(position_rad, dtype=float).tolist(),
        "velocity": [] if velocity_rad_s is None else np.asarray(velocity_rad_s).tolist(),
        "effort": [] if effort_nm is None else np.asarray(effort_nm).tolist(),
    }


def transform_stamped(
    time_ns: int, parent: str, child: str, position_m: np.ndarray, quat_wxyz: np.ndarray
) -> dict[str, Any]:
    """A geometry_msgs/TransformStamped: ``parent`` -> ``child`` at ``position_m`` (3,) m with
    the orientation ``quat_wxyz`` (4,) in MuJoCo's (w, x, y, z), written in ROS's x, y, z, w."""
    x, y, z = (float(v) for v in position_m)
    w, qx, qy, qz = (float(v) for v in quat_wxyz)
    return {
        "header": header(time_ns, parent),
        "child_frame_id": child,
        "transform": {
            "translation": {"x": x, "y": y, "z": z},
            "rotation": {"x": qx, "y": qy, "z": qz, "w": w},
        },
    }


def tf_message(
    time_ns: int,
    parent: str,
    children: Sequence[str],
    positions_m: np.ndarray,
    quats_wxyz: np.ndarray,
) -> dict[str, Any]:
    """A tf2_msgs/TFMessage: ``parent`` -> each of ``children`` at positions (L, 3) m and
    orientations (L, 4) as (w, x, y, z) (see :func:`transform_stamped`)."""
    return {
        "transforms": [
            transform_stamped(time_ns, parent, child, p, q)
            for child, p, q in zip(children, positions_m, quats_wxyz, strict=True)
        ]
    }


def diagnostic_status(
    name: str,
    level: int,
    message: str,
    values: Mapping[str, object],
    hardware_id: str = "",
) -> dict[str, Any]:
    """A diagnostic_msgs/DiagnosticStatus; ``values`` become its key-value strings (a float
    with 6 significant digits, None as an empty string)."""
    return {
        "level": level,
        "name": name,
        "message": message,
        "hardware_id": hardware_id,
        "values": [{"key": key, "value": _text(value)} for key, value in values.items()],
    }


def diagnostic_array(time_ns: int, statuses: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """A diagnostic_msgs/DiagnosticArray of ``statuses`` (see :func:`diagnostic_status`)."""
    return {"header": header(time_ns), "status": list(statuses)}


def _text(value: object) -> str:
    if value is None:
        return ""
    if isinstance(value, float | np.floating):
        return f"{float(value):.6g}"
    return str(value)
