"""The robot on the desk, through the real port: it answers, holds its settings, moves, stops safe.

Run in order (pytest keeps file order); each test opens the port itself, so any one can run
alone. See conftest.py for how to point them at a bus.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from snakebot.backends.chain import ServoBus, ServoChainBackend
from snakebot.backends.chain.ticks import TickConverter
from snakebot.config import RobotConfig
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from snakebot.setup import Link, load_settings, survey

pytestmark = pytest.mark.hardware

WAVE_RAD = 0.15  # small: the test must be safe on a snake lying on a desk
DURATION_S = 2.0


def open_bus(port: str, robot: RobotConfig) -> ServoBus:
    """The robot's bus: its model's family speaks (Dynamixel, or Feetech's scservo_sdk)."""
    bus = ServoBus(port, robot.bus.baud, model=robot.servo.name, protocol=robot.bus.protocol)
    bus.open()
    return bus


LOOK_PAST = 3
"""IDs pinged past the robot's highest where the family has no broadcast ping (Feetech, Dynamixel
Protocol 1.0): a servo left at another ID sits near the chain's."""


def test_every_servo_of_the_robot_answers_and_no_other(port: str, robot: RobotConfig) -> None:
    bus = open_bus(port, robot)
    try:
        found = bus.ping_all(robot.servo_ids)
        if bus.family.broadcast_ping:
            on_bus = bus.broadcast_ping()
        else:
            on_bus = bus.ping_all(range(max(robot.servo_ids) + LOOK_PAST + 1))
    finally:
        bus.close()
    missing = [i for i in robot.servo_ids if i not in found]
    assert not missing, f"servo(s) {missing} do not answer at {robot.bus.baud} bit/s"
    wrong = {i: m for i, m in found.items() if m != robot.servo.model_number}
    assert not wrong, f"servo model numbers {wrong}, expected {robot.servo.model_number}"
    extra = sorted(set(on_bus) - set(robot.servo_ids))
    assert not extra, f"servo(s) {extra} are on the bus but not in {robot.name}"


def test_the_servos_hold_the_settings_the_robot_file_asks_for(
    port: str, robot: RobotConfig
) -> None:
    chain = load_settings(robot)
    with Link(port, chain.baud, model=robot.servo.name) as link:
        diff = survey(link, chain)
    differences = [
        f"servo {d.servo_id} {d.key}: {d.current} (wanted {d.wanted})" for d in diff.differences
    ]
    assert not differences, "settings differ; `snakebot config apply` writes them: " + "; ".join(
        differences
    )
    assert not any(s.hardware_error for s in diff.servos.values()), diff.notes


def test_a_small_wave_runs_for_two_seconds_and_is_tracked(port: str, robot: RobotConfig) -> None:
    gait = make_gait(
        "serpenoid",
        robot.joint_count,
        {"amplitude": WAVE_RAD},
        lower_rad=robot.lower_rad,
        upper_rad=robot.upper_rad,
    )
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    backend = ServoChainBackend(robot, port=port)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # settings advice was checked above
        with backend:
            result = run_gait(
                backend,
                gait,
                SafetyLayer.for_robot(robot),
                RunPlan(duration_s=DURATION_S, rate_hz=100.0),
                metrics,
            )
    summary = result.summary
    assert not result.interrupted
    assert summary["duration_s"] == pytest.approx(DURATION_S, abs=0.05)
    assert float(summary["achieved_rate_hz"]) > 50.0  # type: ignore[arg-type]
    assert float(summary["tracking_rms_rad"]) < WAVE_RAD  # type: ignore[arg-type]
    # A trip means the host fed no instruction for 100 ms; the backend recovers from one (and
    # says so), but more in 2 s means this host cannot drive the bus at this rate.
    assert summary["backend_stats"].get("watchdog_trips", 0) <= 1  # type: ignore[attr-defined]


def test_the_stop_policy_is_left_applied(port: str, robot: RobotConfig) -> None:
    backend = ServoChainBackend(robot, port=port)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        backend.connect()
        backend.close()
    bus = open_bus(port, robot)
    try:
        torque = bus.sync_read("torque_enable", robot.servo_ids)
        watchdog = (
            bus.sync_read("bus_watchdog", robot.servo_ids) if "bus_watchdog" in bus.table else {}
        )
        goals = bus.sync_read("goal_position", robot.servo_ids)
    finally:
        bus.close()
    hold = robot.safety.stop_policy == "hold"
    assert {i: v["torque_enable"] for i, v in torque.items()} == dict.fromkeys(
        robot.servo_ids, int(hold)
    )
    assert {v["bus_watchdog"] for v in watchdog.values()} <= {0}  # disarmed, never tripped
    if hold:
        converter = TickConverter.for_robot(robot)
        safe = converter.goal_ticks(
            np.clip(np.zeros(robot.joint_count), robot.lower_rad, robot.upper_rad)
        )[0]
        assert [goals[i]["goal_position"] for i in robot.servo_ids] == safe
