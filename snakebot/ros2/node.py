"""The ROS 2 node: rclpy publishers and subscriptions around the node's control cycle.

Imported only by ``snakebot ros2`` and :func:`snakebot.ros2.run_node` (it imports rclpy). The
executor spins on a thread of its own: the callbacks turn messages into commands in the
inbox, the parameter callback checks a gait selection; the control cycle (snakebot.ros2.serve)
runs on the calling thread, and the publishers are observers of its cycle records.
"""

from __future__ import annotations

import array
import contextlib
import threading
from collections.abc import Iterator, Sequence
from typing import Any

import rclpy
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import TransformStamped, Twist
from rcl_interfaces.msg import SetParametersResult
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import JointState as JointStateMessage
from trajectory_msgs.msg import JointTrajectory

from snakebot.backends.base import Backend
from snakebot.backends.capabilities import OnBus, ReportsHealth, SensesCurrent
from snakebot.config import RobotConfig
from snakebot.control.cycle import CycleObserver, CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.safety import SafetyLayer
from snakebot.control.summary import run_summary
from snakebot.drive.controller import DriveController, GaitChoice
from snakebot.drive.setup import live_gait
from snakebot.errors import ConfigError, SnakebotError
from snakebot.gaits import check_joint_axes, parse_set_options
from snakebot.ros2 import topics
from snakebot.ros2.commands import (
    CommandDriver,
    CommandedGait,
    CommandError,
    CommandInbox,
    JointTargets,
    joint_index,
    positions_from,
    steer_from,
    trajectory_from,
)
from snakebot.ros2.options import NodeOptions, joint_names, split_gait_params
from snakebot.ros2.serve import ServeResult, serve_commands
from snakebot.session import Snake

_NS = 1_000_000_000


def qos_profile(spec: topics.QosSpec) -> QoSProfile:
    """The rclpy profile of a QoS spec."""
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=spec.depth,
        reliability=ReliabilityPolicy.RELIABLE
        if spec.reliability == "reliable"
        else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.VOLATILE,
    )


def run_node(
    snake: Snake,
    options: NodeOptions | None = None,
    *,
    inbox: CommandInbox | None = None,
    stop_check: Any = None,
    observers: Sequence[CycleObserver] = (),
) -> ServeResult:
    """Serve a connected ``snake`` as a ROS 2 node until a stop (snakebot.ros2.topics lists
    the interface). ``inbox`` takes commands from Python as the subscriptions do (one with a
    command in it starts moving at once); ``stop_check()`` returning a reason stops the node
    (a signal). Ends at the rest pose; leaving the Snake's ``with`` block then applies the stop
    policy. ``observers`` see every cycle's record after the publishers (a recording: see
    snakebot.telemetry.ros2_mcap). Raises GaitError/ConfigError for a gait list that cannot be
    driven (before anything moves) and what the control cycle raises.
    """
    options = options or NodeOptions()
    robot = snake.robot
    if not isinstance(robot, RobotConfig):
        raise ConfigError(robot.name, "", "the ROS node serves a jointed robot, not a soft body")
    choices = options.gait_choices(robot)
    rate = options.rate_hz
    live = live_gait(
        robot,
        rate_hz=rate,
        smoothing_s=options.smoothing_s,
        transition_s=options.transition_s,
        gaits=choices,
    )
    inbox = inbox or CommandInbox()
    driver = CommandDriver(
        CommandedGait(live),
        DriveController(live, choices),
        inbox,
        timeout_s=options.command_timeout_s,
        on_timeout=options.on_timeout,
    )
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    with _ros_node(options) as node:
        bridge = RosBridge(node, robot, snake.backend, inbox, metrics, options, choices[0])
        return serve_commands(
            snake.backend,
            driver,
            SafetyLayer.for_robot(robot),
            rate_hz=rate,
            metrics=metrics,
            observers=(*bridge.observers, *observers),
            stop_check=stop_check,
        )


@contextlib.contextmanager
def _ros_node(options: NodeOptions) -> Iterator[Node]:
    """A node in a context of its own, its executor spinning on a daemon thread; the stop
    signals stay the caller's (rclpy installs no handler)."""
    context = Context()
    args = ["snakebot", *options.ros_args] if options.ros_args else None
    rclpy.init(args=args, context=context, signal_handler_options=SignalHandlerOptions.NO)
    node = Node(options.node_name, context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    thread = threading.Thread(target=_spin, args=(executor,), name="ros2-executor", daemon=True)
    thread.start()
    try:
        yield node
    finally:
        executor.shutdown(timeout_sec=1.0)
        node.destroy_node()
        context.try_shutdown()
        thread.join(timeout=2.0)


def _spin(executor: SingleThreadedExecutor) -> None:
    with contextlib.suppress(ExternalShutdownException):
        executor.spin()


class RosBridge:
    """The node's topics and parameters for one robot on one backend: subscriptions fill
    ``inbox``; ``observers`` are the publishers, one call per cycle record."""

    def __init__(
        self,
        node: Node,
        robot: RobotConfig,
        backend: Backend,
        inbox: CommandInbox,
        metrics: RunMetrics,
        options: NodeOptions,
        first: GaitChoice,
    ) -> None:
        self.node, self.robot, self.backend, self.inbox = node, robot, backend, inbox
        self.metrics, self.options = metrics, options
        self.names = joint_names(robot)
        self.index = joint_index(self.names)
        self._checker = live_gait(robot, rate_hz=options.rate_hz)  # the executor thread's own
        self._offset_ns: int | None = None
        self._next_diagnostics_s: float | None = None
        self._joint_states = self._publisher(JointStateMessage, topics.JOINT_STATES)
        self._joint_message = JointStateMessage(name=list(self.names))
        self._diagnostics = self._publisher(DiagnosticArray, topics.DIAGNOSTICS)
        self._run_metrics = self._publisher(DiagnosticStatus, topics.RUN_METRICS)
        self._body_pose = self._publisher(TransformStamped, topics.BODY_POSE)
        self._pose_message = TransformStamped(child_frame_id=topics.BODY_FRAME)
        self._pose_message.header.frame_id = topics.WORLD_FRAME
        self._subscribe(Twist, topics.CMD_VEL, self._on_cmd_vel)
        self._subscribe(JointStateMessage, topics.JOINT_COMMANDS, self._on_joint_commands)
        self._subscribe(JointTrajectory, topics.JOINT_TRAJECTORY, self._on_trajectory)
        params = ",".join(f"{k}={v}" for k, v in first.params.items())
        declared: list[Parameter[Any]] = [
            node.declare_parameter(topics.PARAM_GAIT, first.name),
            node.declare_parameter(topics.PARAM_GAIT_PARAMS, params),
        ]
        if [p.value for p in declared] != [first.name, params]:  # given with --ros-args -p
            result = self._on_parameters(declared)
            if not result.successful:
                raise ConfigError("ros_args", "", result.reason)
        node.add_on_set_parameters_callback(self._on_parameters)
        self.observers = (self._publish_cycle,)

    # -- outputs ---------------------------------------------------------------------------
    def _publisher(self, kind: Any, topic: topics.Topic) -> Any:
        return self.node.create_publisher(kind, topic.name, qos_profile(topic.qos))

    def _stamp(self, stamp: Time, time_s: float) -> None:
        """Set ``stamp`` to robot time ``time_s`` on the node's clock (offset fixed at the
        first cycle, so stamps differ exactly as the cycles' times do)."""
        if self._offset_ns is None:
            self._offset_ns = self.node.get_clock().now().nanoseconds - round(time_s * _NS)
        total = self._offset_ns + round(time_s * _NS)
        stamp.sec, stamp.nanosec = divmod(total, _NS)

    def _publish_cycle(self, record: CycleRecord) -> None:
        message = self._joint_message
        self._stamp(message.header.stamp, record.time_s)
        state = record.state
        # array('d') is the messages' own sequence type: assigned as is, no per-element check.
        message.position = array.array("d", state.position_rad.tobytes())
        message.velocity = array.array("d", state.velocity_rad_s.tobytes())
        message.effort = array.array("d", state.effort_nm.tobytes())
        self._joint_states.publish(message)
        body = record.body
        if body is not None:
            pose = self._pose_message
            pose.header.stamp = message.header.stamp
            translation, rotation = pose.transform.translation, pose.transform.rotation
            translation.x, translation.y, translation.z = body.com_m.tolist()
            rotation.w, rotation.x, rotation.y, rotation.z = body.head_quat.tolist()
            self._body_pose.publish(pose)
        due = self._next_diagnostics_s
        if due is None or record.time_s >= due:
            self._next_diagnostics_s = record.time_s + topics.DIAGNOSTICS_PERIOD_S
            self._publish_diagnostics(message.header.stamp, record)

    def _publish_diagnostics(self, stamp: Time, record: CycleRecord) -> None:
        summary = run_summary(
            self.metrics,
            self.backend,
            rate_hz=self.options.rate_hz,
            gait_period_s=None,
            interrupted=False,
        )
        summary["commands"] = self.inbox.received
        summary["refused_commands"] = self.inbox.refused
        values = [
            KeyValue(key=key, value=f"{value:.6g}" if isinstance(value, float) else str(value))
            for key, value in summary.items()
            if isinstance(value, int | float | str | bool) or value is None
        ]
        metrics = DiagnosticStatus(
            level=DiagnosticStatus.OK,
            name=f"{self.node.get_name()}: run",
            message=f"{record.cycle} cycles at {record.achieved_rate_hz:.1f} Hz",
            hardware_id=self.robot.name,
            values=values,
        )
        self._run_metrics.publish(metrics)
        array = DiagnosticArray(status=[*self._servo_statuses(), metrics])
        array.header.stamp = stamp
        self._diagnostics.publish(array)

    def _servo_statuses(self) -> list[DiagnosticStatus]:
        backend = self.backend
        health = dict(backend.health()) if isinstance(backend, ReportsHealth) else {}
        if isinstance(backend, SensesCurrent):
            health["current_a"] = backend.present_current_a()
        bus = backend.bus if isinstance(backend, OnBus) else None
        statuses = []
        for joint, (name, servo) in enumerate(zip(self.names, self.robot.servo_ids, strict=True)):
            values = [
                KeyValue(key=key, value=f"{float(reading[joint]):.4g}")
                for key, reading in health.items()
                if len(reading) == len(self.names)
            ]
            errors: list[str] = []
            if bus is not None:
                bits = bus.conditions.get(servo, 0)
                errors = [n for n in bus.family.status_errors(bits) if n != "alert"]
                if servo in bus.alerts and not errors:
                    errors = ["alert bit"]
            level = DiagnosticStatus.ERROR if errors else DiagnosticStatus.OK
            statuses.append(
                DiagnosticStatus(
                    level=level,
                    name=f"{self.node.get_name()}: {name}",
                    message=", ".join(errors) or "OK",
                    hardware_id=f"servo {servo}",
                    values=[*values, KeyValue(key="hardware_errors", value=",".join(errors))],
                )
            )
        return statuses

    # -- inputs (the executor's thread) ----------------------------------------------------
    def _subscribe(self, kind: Any, topic: topics.Topic, callback: Any) -> None:
        self.node.create_subscription(kind, topic.name, callback, qos_profile(topic.qos))

    def _refuse(self, exc: CommandError) -> None:
        self.inbox.refuse()
        self.node.get_logger().warning(f"{exc}; the message was dropped")

    def _on_cmd_vel(self, message: Twist) -> None:
        try:
            self.inbox.put(steer_from(message.linear.x, message.angular.z))
        except CommandError as exc:
            self._refuse(exc)

    def _on_joint_commands(self, message: JointStateMessage) -> None:
        try:
            targets = positions_from(message.name, message.position, self.index, "joint_commands")
        except CommandError as exc:
            self._refuse(exc)
            return
        self.inbox.put(JointTargets(targets))

    def _on_trajectory(self, message: JointTrajectory) -> None:
        points = [
            (p.time_from_start.sec + p.time_from_start.nanosec / _NS, p.positions)
            for p in message.points
        ]
        try:
            trajectory = trajectory_from(message.joint_names, points, self.index)
        except CommandError as exc:
            self._refuse(exc)
            return
        self.inbox.put(trajectory)

    def _on_parameters(self, parameters: Sequence[Parameter[Any]]) -> SetParametersResult:
        given = {p.name: p.value for p in parameters}
        if topics.PARAM_GAIT not in given and topics.PARAM_GAIT_PARAMS not in given:
            return SetParametersResult(successful=True)
        name = str(given.get(topics.PARAM_GAIT, self.node.get_parameter(topics.PARAM_GAIT).value))
        raw = given.get(
            topics.PARAM_GAIT_PARAMS, self.node.get_parameter(topics.PARAM_GAIT_PARAMS).value
        )
        try:
            check_joint_axes(name, [joint.axis for joint in self.robot.joints], self.robot.name)
            params = parse_set_options(
                name, split_gait_params(str(raw)), source=topics.PARAM_GAIT_PARAMS
            )
            self._checker.check(name, params)
        except SnakebotError as exc:
            reason = f"gait {name!r} with {topics.PARAM_GAIT_PARAMS} {raw!r}: {exc}"
            return SetParametersResult(successful=False, reason=reason)
        self.inbox.select(GaitChoice(name, params))
        return SetParametersResult(successful=True)
