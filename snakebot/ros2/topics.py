"""The ROS 2 interface of ``snakebot ros2``, as data: node name, topics, types, QoS, parameters.

The one place these are written down: the node (snakebot.ros2.node) builds its publishers,
subscriptions and parameters from here, and docs/ros2.md and the MCAP writer read them. Plain
data, so importing this never imports rclpy. Topic names are relative: a namespace
(``--ros-args -r __ns:=/snake``) or a remap moves them all.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

NODE_NAME = "snakebot"
"""The node's default name."""

Reliability = Literal["reliable", "best_effort"]
Direction = Literal["publish", "subscribe"]


@dataclass(frozen=True)
class QosSpec:
    """A QoS profile as data: ``reliability``, history keep-last ``depth``, volatile durability.

    Publishers are reliable (a best-effort or a reliable subscriber both connect to them).
    Streamed command inputs subscribe best-effort, the one setting every publisher matches; a
    trajectory, sent once, subscribes reliable so it is not lost.
    """

    reliability: Reliability
    depth: int
    durability: Literal["volatile"] = "volatile"


RELIABLE_10 = QosSpec("reliable", 10)
"""Published outputs: reliable, keep last 10, volatile (ROS's default profile)."""
BEST_EFFORT_1 = QosSpec("best_effort", 1)
"""Streamed commands (cmd_vel, joint_commands): only the newest counts, late ones are stale."""
RELIABLE_1 = QosSpec("reliable", 1)
"""A trajectory: sent once, must arrive; a newer one replaces it."""


@dataclass(frozen=True)
class Topic:
    """One topic of the node: ``name`` (relative), ``type`` (``pkg/msg/Name``), whether the
    node publishes or subscribes, its QoS and when it is published (``rate``: "every cycle",
    "1 Hz", "on the twin, every cycle"; for a subscription what it does)."""

    name: str
    type: str
    direction: Direction
    qos: QosSpec
    rate: str


JOINT_STATES = Topic(
    "joint_states",
    "sensor_msgs/msg/JointState",
    "publish",
    RELIABLE_10,
    "every control cycle: names from the robot file, position rad, velocity rad/s, effort N m, "
    "stamped with the cycle's time",
)
DIAGNOSTICS = Topic(
    "diagnostics",
    "diagnostic_msgs/msg/DiagnosticArray",
    "publish",
    RELIABLE_10,
    "1 Hz: one status per servo (temperature_c, input_voltage_v, current_a, hardware_errors "
    "where the backend reads them) and the run's",
)
RUN_METRICS = Topic(
    "run_metrics",
    "diagnostic_msgs/msg/DiagnosticStatus",
    "publish",
    RELIABLE_10,
    "1 Hz: the run summary so far (cycles, achieved rate, overruns, distance, tracking) as "
    "key/value pairs",
)
BODY_POSE = Topic(
    "body_pose",
    "geometry_msgs/msg/TransformStamped",
    "publish",
    RELIABLE_10,
    "every control cycle on a backend that senses the body (the twin): world -> snakebot_body, "
    "the centre of mass and the head link's orientation. A TransformStamped, not tf2_msgs/"
    "TFMessage on /tf: no tf2_msgs wheel exists on PyPI",
)
JOINT_COMMANDS = Topic(
    "joint_commands",
    "sensor_msgs/msg/JointState",
    "subscribe",
    BEST_EFFORT_1,
    "position targets by joint name (topic_based_hardware_interface's command shape); "
    "through the safety layer",
)
JOINT_TRAJECTORY = Topic(
    "joint_trajectory",
    "trajectory_msgs/msg/JointTrajectory",
    "subscribe",
    RELIABLE_1,
    "a trajectory of position targets, played by time_from_start from its arrival "
    "(linear between points); through the safety layer",
)
CMD_VEL = Topic(
    "cmd_vel",
    "geometry_msgs/msg/Twist",
    "subscribe",
    BEST_EFFORT_1,
    "steers the live gait as snakebot drive's stick does: linear.x the speed (-1..1 of the "
    "fastest the servos allow), angular.z the turn (-1..1, > 0 left)",
)

TOPICS: tuple[Topic, ...] = (
    JOINT_STATES,
    DIAGNOSTICS,
    RUN_METRICS,
    BODY_POSE,
    JOINT_COMMANDS,
    JOINT_TRAJECTORY,
    CMD_VEL,
)
"""Every topic of the node, outputs first."""

BODY_FRAME = "snakebot_body"
"""``child_frame_id`` of the body pose."""
WORLD_FRAME = "world"
"""``header.frame_id`` of the body pose: the twin's world frame."""

PARAM_GAIT = "gait"
"""Parameter (string): the live gait cmd_vel steers, by name (``snakebot gaits`` lists them).
Setting it blends into that gait while cmd_vel steers (else the next cmd_vel starts it); a name
or parameters that cannot be driven are refused with the reason. Until the first command the
node holds the pose the joints started in."""
PARAM_GAIT_PARAMS = "gait_params"
"""Parameter (string): the gait's parameters over its defaults, ``KEY=VALUE`` items separated
by commas or spaces, as ``snakebot drive --set`` takes them (``"amplitude_even=0.5,
wavelength=1.2"``); set together with ``gait`` (setting ``gait`` alone keeps these, and is
refused when they do not fit the new gait)."""

DIAGNOSTICS_PERIOD_S = 1.0
"""Seconds between diagnostics and run-metrics messages."""
DEFAULT_COMMAND_TIMEOUT_S = 1.0
"""Seconds without any command (cmd_vel, joint_commands, joint_trajectory) after which the
node acts on the timeout (see snakebot.ros2.commands.TimeoutAction); armed by the first
command, so a node waiting for its first client never times out."""
