"""Odometry from the servos against the twin's ground truth (docs/estimation.md).

Runs a gait on the twin with the encoders' noise on, feeds every cycle's record to
``ChassisOdometry`` (which reads only the joint angles and, with ``--imu``, the head gyro and
tilt) and compares the estimate with the twin's true centre of mass and true virtual-chassis
heading. Prints one row per case: the distance travelled, the position error as a percentage of
it and the heading error after the run. Then ``run --to 1.5,0.5`` on the twin, the error to the
point against the ground truth.

    python tools/bench_estimation.py              # the table of docs/estimation.md
    python tools/bench_estimation.py --quick      # sidewinding with noise only (CI's check)
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass, replace

import numpy as np

import snakebot
from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.model_builder import link_name
from snakebot.config import RobotConfig
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.estimation import ChainGeometry, ChassisOdometry, OdometryConfig, VirtualChassis
from snakebot.session import resolve_gait


@dataclass(frozen=True)
class Case:
    """One bench run: robot, gait, terrain, encoder noise (rad), whether the IMU is read."""

    name: str
    robot: str
    gait: str
    terrain: str | None = None
    noise_rad: float = 0.003
    imu: bool = True
    duration_s: float = 20.0


CASES = (
    Case("sidewinding, flat, noise, IMU", "snake12", "sidewinding"),
    Case("sidewinding, flat, noise, no IMU", "snake12", "sidewinding", imu=False),
    Case("sidewinding, flat, no noise, no IMU", "snake12", "sidewinding", noise_rad=0, imu=False),
    Case("sidewinding, rough, noise, IMU", "snake12", "sidewinding", terrain="rough"),
    Case("lateral undulation (wheels), flat, noise, IMU", "snake8", "serpenoid"),
    Case("lateral undulation (wheels), flat, noise, no IMU", "snake8", "serpenoid", imu=False),
    Case("lateral undulation (wheels), rough, noise, IMU", "snake8", "serpenoid", terrain="rough"),
)


def noisy(robot: RobotConfig, noise_rad: float) -> RobotConfig:
    """``robot`` with its encoders rounded to whole ticks plus Gaussian noise ``noise_rad``
    (the servo file's ``[twin] encoder_noise_rad`` and ``quantise_encoder``)."""
    if noise_rad <= 0:
        return robot
    physics = robot.servo.physics
    extras = replace(physics.extras, encoder_noise_rad=noise_rad, quantise_encoder=1)
    return replace(robot, servo=replace(robot.servo, physics=replace(physics, extras=extras)))


class Truth:
    """The twin's ground truth each cycle: centre of mass and the true chassis heading."""

    def __init__(self, backend: TwinBackend, robot: RobotConfig, odometry: ChassisOdometry) -> None:
        self.backend = backend
        self.odometry = odometry
        self.estimate: list[tuple[float, float, float]] = []
        self.ids = [backend.model.body(link_name(i)).id for i in range(robot.link_count)]
        self.chassis = VirtualChassis()
        self.com: list[np.ndarray] = []
        self.yaw: list[float] = []

    def __call__(self, record: object) -> None:
        data = self.backend.data
        frame = self.chassis.update(data.xipos[self.ids])
        x = frame.rotation[:, 0]
        self.yaw.append(math.atan2(float(x[1]), float(x[0])))
        self.com.append(data.subtree_com[self.ids[0]].copy())
        pose = self.odometry.pose
        assert pose is not None  # the odometry observes each cycle first
        self.estimate.append((pose.x_m, pose.y_m, pose.yaw_rad))


def run_case(case: Case, seed: int = 0) -> dict[str, object]:
    """One case's figures."""
    robot = noisy(snakebot.load_robot(case.robot), case.noise_rad)
    backend = TwinBackend(robot, terrain=case.terrain, seed=seed)
    odometry = ChassisOdometry(
        ChainGeometry.of_robot(robot),
        OdometryConfig(use_imu=case.imu, radius_m=robot.link.radius_m),
    )
    started = time.perf_counter()
    with backend:
        truth = Truth(backend, robot, odometry)
        _, gait = resolve_gait(robot, case.gait)
        metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
        run_gait(
            backend,
            gait,
            SafetyLayer.for_robot(robot),
            RunPlan(case.duration_s, ramp_out=False),
            metrics,
            observers=[odometry, truth],
        )
    estimate = np.array(truth.estimate)
    true_com = np.array(truth.com)
    true_step = true_com[-1, :2] - true_com[0, :2]
    est_step = estimate[-1, :2] - estimate[0, :2]
    distance = float(np.linalg.norm(true_step))
    error = float(np.linalg.norm(est_step - true_step))
    true_turn = float(np.unwrap(truth.yaw)[-1] - np.unwrap(truth.yaw)[0])
    est_turn = float(estimate[-1, 2] - estimate[0, 2])
    return {
        "case": case.name,
        "distance_m": round(distance, 3),
        "position_error_m": round(error, 3),
        "error_pct_of_distance": round(100 * error / distance, 1) if distance > 0 else None,
        "true_turn_deg": round(math.degrees(true_turn), 1),
        "heading_error_deg": round(math.degrees(est_turn - true_turn), 1),
        "wall_s": round(time.perf_counter() - started, 1),
    }


def run_to_point(point: tuple[float, float] = (1.5, 0.5), seed: int = 0) -> dict[str, object]:
    """``run --to X,Y`` on snake8's serpenoid (the default robot and gait): where the twin's
    true centre of mass ends, after the ramp-out, against the point."""
    from snakebot.cli.goto_options import steered_gait
    from snakebot.session import Snake

    robot = snakebot.load_robot("snake8")
    name, gait = resolve_gait(robot, "serpenoid")
    _, steered, steering = steered_gait(robot, name, gait, f"{point[0]!r},{point[1]!r}")
    started = time.perf_counter()
    backend = TwinBackend(robot, seed=seed)
    with Snake(robot, backend, "twin") as snake:
        start = backend.body_state().com_m.copy()
        steering.odometry.start(snake.read_state())
        summary = snake.run(
            steered, duration_s=60.0, observers=[steering.odometry], stop=steering.reached
        )
        end = backend.body_state().com_m.copy()
    miss = float(np.hypot(*(end[:2] - start[:2] - np.array(point))))
    return {
        "case": f"run --to {point[0]:g},{point[1]:g} (snake8 serpenoid)",
        "stopped_by": summary.extra.get("stopped_by", "the time limit"),
        "time_s": round(summary.duration_s, 2),
        "true_miss_m": round(miss, 3),
        "wall_s": round(time.perf_counter() - started, 1),
    }


def main(argv: list[str] | None = None) -> int:
    """Print the figures (one JSON object per line with ``--json``)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="sidewinding with noise only")
    parser.add_argument("--json", action="store_true", help="one JSON object per case")
    args = parser.parse_args(argv)
    cases = CASES[:1] if args.quick else CASES
    rows = [run_case(case) for case in cases]
    rows.append(run_to_point())
    for row in rows:
        print(json.dumps(row) if args.json else row, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
