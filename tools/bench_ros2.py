"""Benchmark: the ROS 2 node's control cycle against plain `snakebot run`, on the twin at 100 Hz.

Issue 24 (done when the node keeps >= 95 % of the plain rate). snake12, side by side in one
process, the arms in shuffled order each round:
  run     run_gait("sidewinding") at 100 Hz, as Snake.run and `snakebot run` play it: no ROS
  ros2    snakebot.ros2.run_node at 100 Hz, driven (cmd_vel's Steer(0.5, 0) left in its inbox)
          and publishing joint_states, body_pose every cycle and diagnostics each second, with
          a subscriber process reading joint_states the whole time
Both arms stop after ``--seconds`` of wall time (a stop check asked every cycle). Two
pacings: ``paced`` (the twin held to the wall clock, as `snakebot ros2` always runs it and
as `snakebot run --realtime` does): control cycles per wall second over ``--seconds``;
``unpaced`` (as fast as the host goes): the same count, which shows what the node adds to a
cycle; each arm's CPU time per cycle (the whole process: executor and DDS threads too) is
the figure a loaded host disturbs least. Rates are counted from the first cycle to the last
(start-up left out); medians over ``--rounds`` (min-max), the ros2 / run ratio taken within
each round. DDS stays on this machine (snakebot.ros2.loopback_environment).

    python tools/bench_ros2.py [--rounds 3] [--seconds 5]
"""

from __future__ import annotations

import argparse
import os
import random
import signal
import statistics
import subprocess
import sys
import time
from collections.abc import Callable

from snakebot.ros2 import CommandInbox, NodeOptions, Steer, loopback_environment

os.environ.update(loopback_environment())  # before rclpy loads

from snakebot.config import RobotConfig
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.ros2.node import run_node
from snakebot.session import Snake, resolve_gait

ROBOT, GAIT, RATE_HZ = "snake12", "sidewinding", 100.0
SUBSCRIBER = """
import sys, rclpy
from rclpy.node import Node
from sensor_msgs.msg import JointState
rclpy.init()
node = Node("bench_subscriber")
count = [0]
def heard(message):
    count[0] += 1
node.create_subscription(JointState, "joint_states", heard, 10)
print("ready", flush=True)
try:
    rclpy.spin(node)
except BaseException:
    pass
print(count[0], flush=True)
"""


class Clock:
    """Counts cycles and times the first and the last; ``stop`` says when ``seconds`` passed."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self.cycles = 0
        self.first = self.last = 0.0
        self.cpu_first = self.cpu_last = 0.0

    def tick(self, *_: object) -> None:
        now, cpu = time.perf_counter(), time.process_time()
        if self.cycles == 0:
            self.first, self.cpu_first = now, cpu
        self.last, self.cpu_last = now, cpu
        self.cycles += 1

    def stop(self) -> str | None:
        self.tick()
        return "done" if self.last - self.first >= self.seconds else None

    @property
    def rate_hz(self) -> float:
        return (self.cycles - 1) / (self.last - self.first)

    @property
    def cpu_us(self) -> float:
        """CPU time of the whole process (every thread: executor, DDS) per cycle."""
        return (self.cpu_last - self.cpu_first) / (self.cycles - 1) * 1e6


def plain_run(seconds: float, realtime: bool) -> Clock:
    """What ``Snake.run`` (``snakebot run``) does, open-ended: stopped after ``seconds`` of
    wall time as the node arm is, so both count the same stretch of running."""
    clock = Clock(seconds)
    with Snake.prepare(ROBOT, "twin", realtime=realtime) as snake:
        robot = snake.robot
        assert isinstance(robot, RobotConfig)
        _, gait = resolve_gait(robot, GAIT)
        run_gait(
            snake.backend,
            gait,
            SafetyLayer.for_robot(robot),
            RunPlan(duration_s=None, rate_hz=RATE_HZ, ramp_out=False),
            RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
            stop=clock.stop,
        )
    return clock


def node_run(seconds: float, realtime: bool) -> Clock:
    clock = Clock(seconds)
    inbox = CommandInbox()
    inbox.put(Steer(0.5, 0.0))
    options = NodeOptions(rate_hz=RATE_HZ, command_timeout_s=0.0)
    with Snake.prepare(ROBOT, "twin", realtime=realtime) as snake:
        run_node(snake, options, inbox=inbox, stop_check=clock.stop)
    return clock


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=5.0)
    args = parser.parse_args()
    subscriber = subprocess.Popen(
        [sys.executable, "-c", SUBSCRIBER], stdout=subprocess.PIPE, text=True
    )
    assert subscriber.stdout is not None and subscriber.stdout.readline().strip() == "ready"
    arms: dict[str, Callable[[float, bool], Clock]] = {"run": plain_run, "ros2": node_run}
    try:
        for pacing, realtime in (("paced", True), ("unpaced", False)):
            rates: dict[str, list[float]] = {name: [] for name in arms}
            cpu: dict[str, list[float]] = {name: [] for name in arms}
            ratios, cpu_ratios = [], []
            for _ in range(args.rounds):
                order = list(arms)
                random.shuffle(order)
                got = {name: arms[name](args.seconds, realtime) for name in order}
                for name, clock in got.items():
                    rates[name].append(clock.rate_hz)
                    cpu[name].append(clock.cpu_us)
                ratios.append(got["ros2"].rate_hz / got["run"].rate_hz)
                cpu_ratios.append(got["ros2"].cpu_us / got["run"].cpu_us)
            line = ", ".join(
                f"{name} {statistics.median(r):.1f} Hz ({min(r):.1f}-{max(r):.1f}) "
                f"{statistics.median(cpu[name]):.0f} us CPU/cycle"
                for name, r in rates.items()
            )
            print(
                f"{pacing:8s} {line}; rate ros2/run {statistics.median(ratios):.3f} "
                f"({min(ratios):.3f}-{max(ratios):.3f}), CPU ros2/run "
                f"{statistics.median(cpu_ratios):.2f}",
                flush=True,
            )
    finally:
        subscriber.send_signal(signal.SIGINT)
        out, _ = subscriber.communicate(timeout=30)
    print(f"subscriber read {out.strip() or '?'} joint_states messages")


if __name__ == "__main__":
    main()
