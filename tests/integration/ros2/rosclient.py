"""A second ROS 2 node for the tests, and `snakebot ros2` in a subprocess, as a user runs it.

Every rclpy process here keeps DDS on this machine: localhost discovery, Fast DDS, and the
loopback-only profile beside this file (the same settings the node gets from ``--loopback``).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).parent
ROOT = HERE.parents[2]
LOOPBACK = {
    "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
    "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
    "FASTDDS_DEFAULT_PROFILES_FILE": str(HERE / "fastdds-loopback.xml"),
}
os.environ.update(LOOPBACK)  # before rclpy loads anywhere in the test process

import rclpy  # noqa: E402
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import TransformStamped, Twist  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from rclpy.signals import SignalHandlerOptions  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint  # noqa: E402

STARTUP_S = 120.0
"""Longest wait for the node's first joint_states: MuJoCo, the model and DDS discovery on a
loaded 2-core machine."""


@dataclass
class Received:
    """What the client heard: joint states as (stamp s, positions (N,), arrival s)."""

    joint_states: list[tuple[float, np.ndarray, float]] = field(default_factory=list)
    body_pose: list[tuple[float, np.ndarray]] = field(default_factory=list)
    diagnostics: list[DiagnosticArray] = field(default_factory=list)


class Client:
    """The test's node: publishes commands, subscribes to the outputs (on its own thread)."""

    def __init__(self, name: str = "snakebot_test_client") -> None:
        self.context = Context()
        rclpy.init(context=self.context, signal_handler_options=SignalHandlerOptions.NO)
        self.node = Node(name, context=self.context)
        self.heard = Received()
        self.lock = threading.Lock()
        reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self.cmd_vel = self.node.create_publisher(Twist, "cmd_vel", reliable)
        self.joint_commands = self.node.create_publisher(JointState, "joint_commands", reliable)
        self.trajectory = self.node.create_publisher(JointTrajectory, "joint_trajectory", reliable)
        # A deep reader history: DDS's own threads keep receiving while this (Python, GIL-bound)
        # executor is starved on a loaded machine, so a late spin loses nothing.
        deep = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self.node.create_subscription(JointState, "joint_states", self._on_joints, deep)
        self.node.create_subscription(TransformStamped, "body_pose", self._on_pose, reliable)
        self.node.create_subscription(DiagnosticArray, "diagnostics", self._on_diag, reliable)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self) -> None:
        with suppress(ExternalShutdownException):
            self.executor.spin()

    def _on_joints(self, message: JointState) -> None:
        stamp = message.header.stamp.sec + message.header.stamp.nanosec * 1e-9
        with self.lock:
            self.heard.joint_states.append(
                (stamp, np.array(message.position, dtype=float), time.monotonic())
            )

    def _on_pose(self, message: TransformStamped) -> None:
        t, q = message.transform.translation, message.transform.rotation
        with self.lock:
            self.heard.body_pose.append(
                (
                    message.header.stamp.sec + message.header.stamp.nanosec * 1e-9,
                    np.array([t.x, t.y, t.z, q.w, q.x, q.y, q.z]),
                )
            )

    def _on_diag(self, message: DiagnosticArray) -> None:
        with self.lock:
            self.heard.diagnostics.append(message)

    def joint_states(self) -> list[tuple[float, np.ndarray, float]]:
        with self.lock:
            return list(self.heard.joint_states)

    def wait_for(self, what: Callable[[], bool], timeout_s: float, why: str) -> None:
        deadline = time.monotonic() + timeout_s
        while not what():
            assert time.monotonic() < deadline, f"timed out waiting for {why}"
            time.sleep(0.02)

    def steer(self, speed: float, turn: float) -> None:
        message = Twist()
        message.linear.x, message.angular.z = speed, turn
        self.cmd_vel.publish(message)

    def command_joints(self, names: Sequence[str], positions: Sequence[float]) -> None:
        self.joint_commands.publish(JointState(name=list(names), position=list(positions)))

    def send_trajectory(
        self, names: Sequence[str], points: Sequence[tuple[float, Sequence[float]]]
    ) -> None:
        message = JointTrajectory(joint_names=list(names))
        for time_s, positions in points:
            point = JointTrajectoryPoint(positions=list(positions))
            point.time_from_start.sec = int(time_s)
            point.time_from_start.nanosec = round((time_s - int(time_s)) * 1e9)
            message.points.append(point)
        self.trajectory.publish(message)

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        self.context.try_shutdown()
        self.thread.join(timeout=5.0)


@contextmanager
def client() -> Iterator[Client]:
    made = Client()
    try:
        yield made
    finally:
        made.close()


class NodeProcess:
    """`python -m snakebot ros2 ... --loopback --json` running; ``finish`` collects it."""

    def __init__(self, proc: subprocess.Popen[str]) -> None:
        self.proc = proc
        self.out = ""
        self.err = ""

    def running(self) -> bool:
        return self.proc.poll() is None

    def interrupt(self, signum: int = signal.SIGINT) -> None:
        if self.running():
            self.proc.send_signal(signum)

    def finish(self, timeout_s: float = 90.0) -> dict[str, Any]:
        """Wait for the exit; the JSON summary it printed ({} when none)."""
        self.out, self.err = self.proc.communicate(timeout=timeout_s)
        lines = [line for line in self.out.splitlines() if line.startswith("{")]
        return json.loads(lines[-1]) if lines else {}


@contextmanager
def ros2_node(*args: str) -> Iterator[NodeProcess]:
    env = {**os.environ, **LOOPBACK, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, "-m", "snakebot", "ros2", "--loopback", "--json", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        cwd=ROOT,
    )
    node = NodeProcess(proc)
    try:
        yield node
    finally:
        if node.running():
            node.interrupt()
            try:
                node.finish(timeout_s=60.0)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
