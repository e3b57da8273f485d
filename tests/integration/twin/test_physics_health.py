"""Honest physics checks on the twin (issue 12 item 3): the audit's cases each end in a documented
warning or a typed error, with the right time."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import numpy.typing as npt
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.health import HealthMonitor
from snakebot.backends.twin.readouts import Capsules
from snakebot.config import RobotConfig, load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.errors import PhysicsHealthError, SimulationDivergedError
from snakebot.gaits import Gait, make_gait
from snakebot.types import JointCommand
from tests.conftest import edit_robot
from tests.integration.twin.robots import with_gains


def test_divergence_reports_the_time_it_happened_not_the_time_after_mujocos_reset() -> None:
    # The audit: "diverged at t=0.0200 s" for a run MuJoCo warned about at 1.24 s. MuJoCo resets
    # the state (time 0) and keeps stepping the rest of the control period.
    with TwinBackend(load_robot("snake8")) as twin:
        for _ in range(62):
            twin.send_command(JointCommand(np.full(8, 0.1)))
            twin.advance(0.02)
        assert twin.data.time == pytest.approx(1.24)
        twin.data.qvel[6] = 1e12
        with pytest.raises(SimulationDivergedError) as caught:
            twin.advance(0.02)
    assert caught.value.time_s == pytest.approx(1.24, abs=0.0021)
    assert "diverged at t=1.24" in str(caught.value)


def snakebot(*argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "snakebot", *argv], capture_output=True, text=True, timeout=120
    )


def test_a_capsule_sinking_into_the_floor_at_accepted_settings_is_a_typed_error_with_its_time(
    config_dir: Path, tmp_path: Path
) -> None:
    # The audit: floor penetration up to 20.7 mm for a 22 mm capsule at settings the robot file
    # accepts (the highest gain registers, a tiny armature, the largest timestep), exit 0.
    robot = edit_robot(config_dir, "snake8", "position_p = 640", "position_p = 16383")
    edit_robot(config_dir, "snake8", "position_d = 4000", "position_d = 16383")
    edit_robot(config_dir, "snake8", "timestep_s = 0.002", "timestep_s = 0.02")
    edit_robot(
        config_dir,
        "snake8",
        "[joint_defaults]",
        "[twin.servo]\narmature_kgm2 = 0.00001\n\n[joint_defaults]",
    )
    log = tmp_path / "run.csv"
    run = snakebot(
        "run", "--robot", str(robot), "--rate", "50", "--duration", "10", "--log", str(log)
    )
    assert run.returncode == 1, run.stdout + run.stderr
    assert "physics health: penetration at t=" in run.stderr
    assert "capsule radius 22.0 mm" in run.stderr
    assert log.read_text().count("\n") > 10  # the telemetry taken stays on disk


def test_penetration_past_the_warning_threshold_is_reported_in_the_summary() -> None:
    robot = with_gains(load_robot("snake8"), 16383, 16383)
    robot = dataclasses.replace(robot, twin=dataclasses.replace(robot.twin, timestep_s=0.02))
    summary = run(robot, "serpenoid", 5.0, rate_hz=50)
    physics = summary["physics"]
    assert 0.25 * 22 < physics["max_floor_penetration_mm"] < 0.5 * 22
    assert any("floor penetration" in w for w in physics["warnings"])


def run(
    robot: RobotConfig, gait: str | Gait, duration_s: float, rate_hz: float = 100.0, **twin: object
) -> dict[str, Any]:
    """``gait`` on the twin of ``robot``; the run's summary."""
    if isinstance(gait, str):
        gait = make_gait(gait, robot.joint_count, {})
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    with TwinBackend(robot, **twin) as backend:  # type: ignore[arg-type]
        result = run_gait(
            backend, gait, SafetyLayer.for_robot(robot), RunPlan(duration_s, rate_hz), metrics
        )
    return result.summary


class Chatter(Gait):
    """Every joint's goal flips between +-amplitude each control cycle: the control Nyquist."""

    def __init__(self, joint_count: int, amplitude_rad: float, rate_hz: float) -> None:
        self.joint_count, self.amplitude, self.rate_hz = joint_count, amplitude_rad, rate_hz

    def targets(self, time_s: float | npt.ArrayLike) -> np.ndarray:
        sign = 1.0 if round(float(time_s) * self.rate_hz) % 2 == 0 else -1.0  # type: ignore[arg-type]
        return np.full(self.joint_count, sign * self.amplitude)


class Pose(Gait):
    """Hold one pose (N,) rad."""

    def __init__(self, pose_rad: np.ndarray) -> None:
        self.joint_count, self.pose = len(pose_rad), pose_rad

    def targets(self, time_s: float | npt.ArrayLike) -> np.ndarray:
        return self.pose.copy()


def test_joints_chattering_at_the_control_nyquist_rate_are_a_warning_with_the_work_put_in() -> None:
    # The audit: joints chattering near the control Nyquist rate, with hundreds of joules of
    # positive work, ended with exit 0 and nothing said. A light, stiff servo (no armature, the
    # highest P register) follows goals that flip every cycle.
    robot = with_gains(load_robot("snake8"), 16383, 0)
    physics = dataclasses.replace(robot.servo.physics, armature_kgm2=0.0002)
    robot = dataclasses.replace(robot, servo=dataclasses.replace(robot.servo, physics=physics))
    summary = run(robot, Chatter(8, 0.3, 100.0), 5.0)
    health = summary["physics"]
    assert health["chatter"] > 0.8
    assert any("chatter" in w and "Nyquist" in w for w in health["warnings"])
    assert health["energy_injected_j"] > 10.0
    assert any("W on average" in w for w in health["warnings"])
    calm = run(robot, "serpenoid", 5.0)["physics"]
    assert calm["chatter"] < 0.05 and calm["warnings"] == []


def test_servos_pressed_into_each_other_report_self_penetration_and_their_stall() -> None:
    # The audit: self-penetration with two servos stalled at 1.4 N·m for the rest of the run.
    # Five joints bent to their limits press the middle modules into each other.
    pose = np.array([0, 1.5, 1.5, 1.5, 1.5, 1.5, 0, 0])
    summary = run(load_robot("snake8"), Pose(pose), 6.0)
    physics = summary["physics"]
    assert 0.25 * 22 < physics["max_self_penetration_mm"] < 0.5 * 22
    assert physics["longest_stall_s"] > 4.0
    assert any("self penetration" in w for w in physics["warnings"])
    assert any("stalled at its torque limit" in w for w in physics["warnings"])


def test_a_snake_folded_into_itself_ends_in_the_typed_error() -> None:
    with pytest.raises(PhysicsHealthError, match="penetration at t=") as caught:
        run(load_robot("snake8"), Pose(np.full(8, 1.5)), 6.0)
    assert 0.5 < caught.value.time_s < 6.0


def test_joint_speed_beyond_the_torque_speed_line_is_a_typed_error_with_its_time() -> None:
    # The audit: joint speeds above the servo's no-load speed, exit 0.
    with TwinBackend(load_robot("snake8")) as twin:
        monitor = twin.physics_monitor
        assert monitor is not None
        twin.advance(0.01)
        twin.data.qvel[twin._dof_index[3]] = 1.2 * 5.969  # a warning, not yet an error
        monitor.sample(twin.data, 0.01, np.zeros(8))
        assert any("beyond the servo's no-load speed" in w for w in monitor.summary()["warnings"])
        twin.data.qvel[twin._dof_index[3]] = 1.6 * 5.969
        with pytest.raises(PhysicsHealthError, match=r"joint speed at t=0\.0100 s: 9\.55 rad/s"):
            monitor.sample(twin.data, 0.01, np.zeros(8))


def test_more_power_than_a_servo_has_for_a_second_is_a_typed_error() -> None:
    with TwinBackend(load_robot("snake8")) as twin:
        monitor = twin.physics_monitor
        assert monitor is not None
        twin.data.qvel[twin._dof_index] = 1.0
        torque = np.zeros(8)
        torque[0] = 1.4  # 1.4 W against a 2.09 W peak: a warning
        for _ in range(100):
            monitor.sample(twin.data, 0.01, torque)
        assert any("W on average" in w for w in monitor.summary()["warnings"])
        torque[0] = 3.0  # 3 W: no servo on its torque-speed line gives that
        with pytest.raises(PhysicsHealthError, match=r"energy injected.*3\.00 W over 1 s"):
            for _ in range(100):
                monitor.sample(twin.data, 0.01, torque)


def test_the_compiled_scan_reads_every_cycle_what_the_python_pass_reads() -> None:
    """health_c's C scan against the Python pass on the same MjData every cycle: grounded and
    penetrating (a serpenoid), modules pressed into each other (self contacts), and a snake
    falling from 0.2 m (no contact: the capsules' lowest point). Same numbers to the bit."""
    from snakebot.backends.twin.health import PythonScan
    from snakebot.backends.twin.health_c import ContactScan

    robot = load_robot("snake8")
    seen = {"grounded": 0, "airborne": 0, "self": 0}
    serpenoid = make_gait("serpenoid", 8, {})
    pressed = np.array([0, 1.5, 1.5, 1.5, 1.5, 1.5, 0, 0])
    for case in ("serpenoid", "pressed", "falling"):
        with TwinBackend(robot, health=None) as twin:  # the landing would stop a checked run
            model, data = twin.model, twin.data
            capsules = Capsules.of_modules(model, robot.link_count)
            is_link = np.zeros(model.ngeom, dtype=bool)
            is_link[capsules.geoms] = True
            compiled = ContactScan(model, capsules, is_link, twin._dof_index)
            python = PythonScan(capsules, is_link, twin._dof_index)
            if case == "falling":
                data.qpos[2] += 0.2
                mujoco.mj_forward(model, data)
            for k in range(150):
                goal = pressed if case == "pressed" else serpenoid.targets(k * 0.01)
                twin.send_command(JointCommand(0.5 * goal if case == "falling" else goal))
                twin.advance(0.01)
                got, want = compiled.scan(data), python.scan(data)
                assert got == want, (case, k)
                seen["grounded" if got[2] else "airborne"] += 1
                seen["self"] += got[1] > -math.inf
    assert all(count > 10 for count in seen.values()), seen


def test_a_run_reports_the_same_health_with_the_scan_in_c_or_in_python() -> None:
    robot = load_robot("snake8")
    summaries = []
    for compiled in (True, False):
        metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
        with TwinBackend(robot) as twin:
            twin.physics_monitor = HealthMonitor(
                twin.model,
                Capsules.of_modules(twin.model, robot.link_count),
                twin._dof_index,
                twin._head_id,
                no_load_speed_rad_s=5.969,
                torque_limit_nm=1.4,
                compiled=compiled,
            )
            kind = type(twin.physics_monitor._scanner).__name__
            assert kind == ("ContactScan" if compiled else "PythonScan")
            gait = make_gait("serpenoid", robot.joint_count, {})
            plan = RunPlan(duration_s=3.0, rate_hz=100.0)
            run_gait(twin, gait, SafetyLayer.for_robot(robot), plan, metrics)
            summaries.append(twin.physics_monitor.summary())
    assert summaries[0] == summaries[1]
    assert summaries[0]["max_floor_penetration_mm"] > 0.0
