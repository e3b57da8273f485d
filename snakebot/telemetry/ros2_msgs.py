"""The ROS 2 messages a snakebot recording carries: their definitions, topics and CDR bytes.

No ROS import: each message is encoded to CDR here (:mod:`snakebot.telemetry.cdr`), and each
definition is the ``.msg`` text of the standard type with its dependencies appended the way
rosbag2 stores them (a line of 80 ``=``, then ``MSG: pkg/Type``), so rosbag2, Foxglove and
rosbags decode the file with no snakebot installed. The fields and
their order are those of the ROS 2 Kilted messages (sensor_msgs, diagnostic_msgs, tf2_msgs,
geometry_msgs, std_msgs, builtin_interfaces); the tests decode what is written against the
type store of a ROS installation's definitions (rosbags), not only against this text.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from snakebot.telemetry.cdr import CdrWriter, fill_stamp

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


@dataclass(frozen=True)
class Status:
    """A diagnostic_msgs/DiagnosticStatus: ``level`` (OK, WARN, ERROR, STALE), ``name``,
    ``message``, ``hardware_id`` and the key-value strings ``values``."""

    level: int
    name: str
    message: str
    hardware_id: str
    values: tuple[tuple[str, str], ...]


def diagnostic_status(
    name: str,
    level: int,
    message: str,
    values: Mapping[str, object],
    hardware_id: str = "",
) -> Status:
    """A status whose ``values`` become key-value strings (a float with 6 significant digits,
    None as an empty string)."""
    pairs = tuple((key, _text(value)) for key, value in values.items())
    return Status(level, name, message, hardware_id, pairs)


class JointStates:
    """sensor_msgs/JointState messages in CDR for joints ``names`` (head to tail): the layout
    is made once, each message fills in its stamp and arrays. ``measured``: with velocities and
    efforts (else those are sent empty, as ROS does for what is not measured)."""

    def __init__(self, names: Sequence[str], *, measured: bool = True) -> None:
        self.names = tuple(names)
        self.measured = measured
        zeros = np.zeros(len(self.names))
        cdr = CdrWriter()
        self._stamp = cdr.header(0)
        cdr.strings(self.names)
        self._arrays = [cdr.float64s(zeros)]
        self._arrays += [cdr.float64s(zeros if measured else ()) for _ in range(2)]
        self._template = cdr.data()
        self._size = 8 * len(self.names)

    def __call__(
        self,
        time_ns: int,
        position_rad: np.ndarray,
        velocity_rad_s: np.ndarray | None = None,
        effort_nm: np.ndarray | None = None,
    ) -> bytes:
        """One message: positions (N,) rad and, when ``measured``, velocities (N,) rad/s and
        efforts (N,) N m; ValueError for arrays of another length."""
        arrays = [position_rad]
        if self.measured:
            if velocity_rad_s is None or effort_nm is None:
                raise ValueError("measured joint states need velocities and efforts")
            arrays += [velocity_rad_s, effort_nm]
        buffer = bytearray(self._template)
        fill_stamp(buffer, self._stamp, time_ns)
        for offset, values in zip(self._arrays, arrays, strict=False):
            data = np.ascontiguousarray(values, dtype="<f8").tobytes()
            if len(data) != self._size:
                raise ValueError(f"{len(data) // 8} values for {len(self.names)} joints")
            buffer[offset : offset + self._size] = data
        return bytes(buffer)


class Transforms:
    """``parent`` -> each of ``children`` in CDR: a tf2_msgs/TFMessage, or with one child and
    ``single`` a geometry_msgs/TransformStamped. The layout is made once; each message fills in
    the stamp and the poses."""

    def __init__(self, parent: str, children: Sequence[str], *, single: bool = False) -> None:
        if single and len(children) != 1:
            raise ValueError(f"a TransformStamped has one child, not {len(children)}")
        cdr = CdrWriter()
        if not single:
            cdr.uint32(len(children))
        self._stamps: list[int] = []
        self._poses: list[int] = []
        for child in children:
            self._stamps.append(cdr.header(0, parent))
            cdr.string(child)
            self._poses.append(cdr.float64(0.0))
            for _ in range(6):
                cdr.float64(0.0)
        self._template = cdr.data()

    def __call__(self, time_ns: int, positions_m: np.ndarray, quats_wxyz: np.ndarray) -> bytes:
        """One message: positions (L, 3) m and orientations (L, 4) in MuJoCo's (w, x, y, z)
        order (ROS's is x, y, z, w); (3,) and (4,) for a single transform."""
        poses = np.empty((len(self._poses), 7), dtype="<f8")
        poses[:, :3] = np.reshape(positions_m, (-1, 3))
        quats = np.reshape(quats_wxyz, (-1, 4))
        poses[:, 3:6], poses[:, 6] = quats[:, 1:], quats[:, 0]
        buffer = bytearray(self._template)
        for stamp, offset, pose in zip(self._stamps, self._poses, poses, strict=True):
            fill_stamp(buffer, stamp, time_ns)
            buffer[offset : offset + 56] = pose.tobytes()
        return bytes(buffer)


def _status(cdr: CdrWriter, status: Status) -> None:
    cdr.uint8(status.level)
    cdr.string(status.name)
    cdr.string(status.message)
    cdr.string(status.hardware_id)
    cdr.uint32(len(status.values))
    for key, value in status.values:
        cdr.string(key)
        cdr.string(value)


def diagnostic_status_message(status: Status) -> bytes:
    """A diagnostic_msgs/DiagnosticStatus in CDR."""
    cdr = CdrWriter()
    _status(cdr, status)
    return cdr.data()


def diagnostic_array(time_ns: int, statuses: Sequence[Status]) -> bytes:
    """A diagnostic_msgs/DiagnosticArray of ``statuses`` in CDR."""
    cdr = CdrWriter()
    cdr.header(time_ns)
    cdr.uint32(len(statuses))
    for status in statuses:
        _status(cdr, status)
    return cdr.data()


def _text(value: object) -> str:
    if value is None:
        return ""
    if isinstance(value, float | np.floating):
        return f"{float(value):.6g}"
    return str(value)
