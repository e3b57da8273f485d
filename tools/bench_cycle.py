"""Benchmark: the controller's own cost per control cycle, with a backend where time costs nothing.

``run_gait`` drives a serpenoid on a backend that stores the command and adds the period to its
clock (no physics, no bus), so what is timed is the cycle itself: gait, safety layer, schedule,
metrics, records. Prints the median (and min) µs per cycle over the repeats. Run it against
another tree to compare (the script uses only run_gait's public API):

    python tools/bench_cycle.py [--repeats 7] [--seconds 50] [--joints 8]
    PYTHONPATH=/path/to/other/checkout python tools/bench_cycle.py
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from snakebot.backends.base import Backend
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from snakebot.types import JointState, PDGains


class NullBackend(Backend):
    """N joints that reach every command at once; time advances by the requested period."""

    def __init__(self, joints: int) -> None:
        super().__init__()
        self.joint_count = joints
        self.now_s = 0.0
        self.position = np.zeros(joints)

    def _connect(self) -> None:
        pass

    def _close(self) -> None:
        pass

    def _read_state(self) -> JointState:
        zeros = np.zeros(self.joint_count)
        return JointState(self.now_s, self.position.copy(), zeros, zeros)

    def _send_command(self, position_rad: np.ndarray) -> None:
        self.position = position_rad

    def _set_gains(self, gains: PDGains) -> None:
        pass

    def _set_torque(self, enabled: bool) -> None:
        pass

    def _advance(self, dt_s: float) -> None:
        self.now_s += dt_s


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--seconds", type=float, default=50.0, help="robot seconds per repeat")
    parser.add_argument("--joints", type=int, default=8)
    args = parser.parse_args()
    robot = load_robot("snake8")
    lower, upper = np.full(args.joints, -1.5), np.full(args.joints, 1.5)
    per_cycle_us = []
    for _ in range(args.repeats):
        backend = NullBackend(args.joints)
        metrics = RunMetrics(args.joints, robot.body_length_m, robot.total_mass_kg)
        safety = SafetyLayer(lower, upper, robot.max_speed_rad_s, robot.safety.ramp_s)
        with backend:
            start = time.perf_counter()
            run_gait(
                backend,
                make_gait("serpenoid", args.joints),
                safety,
                RunPlan(args.seconds, ramp_out=False),
                metrics,
            )
            per_cycle_us.append((time.perf_counter() - start) / metrics.cycles * 1e6)
    print(
        f"{args.joints} joints, {args.repeats} x {args.seconds:g} s at 100 Hz: "
        f"{statistics.median(per_cycle_us):.1f} us/cycle median (min {min(per_cycle_us):.1f})"
    )


if __name__ == "__main__":
    main()
