"""The twin's compiled control period (period_c) against the Python path it replaces.

One C call per period steps the physics and reads the period out (positions, speeds, servo
torques, work, COM, head orientation and rate, the health scan, the divergence counters). What a
user sees must not depend on whether a C compiler was there: every state, body state, record,
health figure and run summary is the Python path's to the bit.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.config import RobotConfig, load_robot
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.errors import SimulationDivergedError
from snakebot.gaits import make_gait
from snakebot.types import JointCommand

FOLD = np.array([0, 1.5, 1.5, 1.5, 1.5, 1.5, 0, 0])  # presses modules 2..5 into each other


def with_extras(config_dir: Path) -> RobotConfig:
    """snake8 with every optional servo part on: current, battery sag, encoder ticks and noise,
    gyro noise (the paths where read_state and body_state do more than copy)."""
    servo = config_dir / "servos" / "xl430-w250.toml"
    text = servo.read_text().replace("quantise_encoder = 1", "")
    extras = "stall_current_a = 1.3\nquantise_encoder = 1\nencoder_noise_rad = 0.002\n"
    servo.write_text(text + f"\n[twin]\n{extras}imu_gyro_noise_rad_s = 0.01\n")
    robot = config_dir / "robots" / "snake8.toml"
    robot.write_text(
        robot.read_text().replace(
            "[joint_defaults]", "[twin.servo]\nbattery_resistance_ohm = 0.5\n\n[joint_defaults]", 1
        )
    )
    return load_robot(robot)


def flat(record: CycleRecord) -> bytes:
    """Every number of a record, as bytes."""
    state, body = record.state, record.body
    parts = [
        np.array([record.time_s, record.period_s, record.achieved_rate_hz]),
        record.target_rad,
        record.command_rad,
        state.position_rad,
        state.velocity_rad_s,
        state.effort_nm,
    ]
    parts += [] if state.positive_work_j is None else [state.positive_work_j]
    parts += [] if record.work_j is None else [record.work_j]
    if body is not None:
        parts += [body.com_m, body.head_quat]
        parts += [] if body.head_gyro_rad_s is None else [body.head_gyro_rad_s]
    return b"".join(np.ascontiguousarray(p, dtype=float).tobytes() for p in parts)


def run_both(robot: RobotConfig, gait: str, seconds: float, lift_m: float = 0.0) -> list:
    """The same run with the compiled period and in Python: (records, summary, health) each."""
    results = []
    for compiled in (True, False):
        records: list[bytes] = []
        metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
        with TwinBackend(robot) as twin:
            assert twin._period is not None, "the test needs a C compiler"
            if not compiled:
                twin._period = None
            if lift_m:
                twin.data.qpos[2] += lift_m
                mujoco.mj_forward(twin.model, twin.data)
            plan = RunPlan(duration_s=seconds, rate_hz=100.0)
            result = run_gait(
                twin,
                make_gait(gait, robot.joint_count, {}),
                SafetyLayer.for_robot(robot),
                plan,
                metrics,
                observers=[lambda record, kept=records: kept.append(flat(record))],
            )
            results.append((records, result.summary, twin.physics_health()))
    return results


def test_a_serpenoid_run_is_the_python_paths_to_the_bit() -> None:
    (fast, fast_summary, fast_health), (slow, slow_summary, slow_health) = run_both(
        load_robot("snake8"), "serpenoid", 3.0
    )
    assert len(fast) > 300
    assert fast == slow
    assert fast_summary == slow_summary
    assert fast_health == slow_health
    assert fast_summary["positive_work_j"] > 0 and fast_summary["distance_m"] > 0.01


def test_a_snake_dropped_from_above_the_ground_reads_its_clearance_the_same() -> None:
    """No contact for the first cycles: the health scan's lowest-capsule path."""
    (fast, _, fast_health), (slow, _, slow_health) = run_both(
        load_robot("snake8"), "serpenoid", 1.0, lift_m=0.05
    )
    assert fast == slow and fast_health == slow_health
    assert fast_health is not None and fast_health["airborne_fraction"] > 0.0


def test_every_optional_servo_part_reads_the_same(config_dir: Path) -> None:
    """Current draw, battery sag (gains change every cycle, so read_state recomputes the
    torque), encoder ticks and noise, gyro noise: the same bits either way."""
    (fast, fast_summary, fast_health), (slow, slow_summary, slow_health) = run_both(
        with_extras(config_dir), "serpenoid", 2.0
    )
    assert fast == slow
    assert fast_summary == slow_summary and fast_health == slow_health
    assert fast_health is not None and "lowest_supply_voltage_v" in fast_health


def test_modules_pressed_together_and_a_second_read_give_the_same_states() -> None:
    """Self contact, and states read twice, body states read between: each read is a new array
    with the same numbers, whichever path made it."""
    robot = load_robot("snake8")
    seen = []
    for compiled in (True, False):
        with TwinBackend(robot) as twin:
            if not compiled:
                twin._period = None
            reads = []
            for k in range(150):
                twin.send_command(JointCommand(FOLD * min(1.0, k / 100)))
                twin.advance(0.01)
                first, body, second = twin.read_state(), twin.body_state(), twin.read_state()
                assert first.position_rad is not second.position_rad
                assert not np.shares_memory(first.effort_nm, second.effort_nm)
                assert np.array_equal(first.effort_nm, second.effort_nm)
                reads.append(first.position_rad.tobytes() + first.effort_nm.tobytes())
                reads.append(body.com_m.tobytes() + second.velocity_rad_s.tobytes())
            health = twin.physics_health()
            seen.append((reads, health))
    assert seen[0] == seen[1]
    health = seen[0][1]
    assert health is not None and health["max_self_penetration_mm"] > 0.0


def test_a_divergence_inside_the_compiled_period_is_the_typed_error_at_its_time() -> None:
    """MuJoCo resets an unstable simulation and steps on; the period reports when it happened,
    as the Python path does."""
    robot = load_robot("snake8")
    times = []
    for compiled in (True, False):
        with TwinBackend(robot, health=None) as twin:
            if not compiled:
                twin._period = None
            for _ in range(3):
                twin.advance(0.01)
            twin.data.qvel[:] = 1e30  # nothing finite comes out of the next step
            with pytest.raises(SimulationDivergedError) as caught:
                twin.advance(0.01)
            times.append(caught.value.time_s)
    assert times[0] == times[1] == pytest.approx(0.03, abs=1e-9)
