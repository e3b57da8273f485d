"""Step tests and excitation records go through the control loop behind a clip-only safety layer.

Real dynamixel_sdk over the in-process emulator on its virtual clock (snake12 at 100 Hz): what
reaches the servo's Goal Position register is the table, a step in one cycle, never beyond the
joint limits; and ``sysid --record`` logs the twin's body (COM, IMU) as ``run --log`` does.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from snakebot.backends.chain import ServoChainBackend
from snakebot.backends.chain.ticks import TickConverter
from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.control.cycle import CycleRecord
from snakebot.control.runner import play_commands
from snakebot.control.safety import SafetyLayer
from snakebot.emulation import EmulatedChain, make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.telemetry import read_log
from snakebot.tuning.excitation import chirp_plan, record
from snakebot.tuning.gains import play

JOINT = 3


@pytest.fixture
def chain() -> Iterator[tuple[EmulatedChain, str]]:
    robot = load_robot("snake12")
    chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud=robot.bus.baud)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    with registered(chain) as url:
        yield chain, url


def test_a_step_table_reaches_the_servo_in_one_cycle_and_never_beyond_its_limit(
    chain: tuple[EmulatedChain, str],
) -> None:
    emulated, url = chain
    robot = load_robot("snake12")
    table = np.zeros((30, 12))
    table[5:20, JOINT] = 0.5  # 50 rad/s in one 10 ms cycle: the run's slew limit would refuse
    table[20:, JOINT] = 10.0  # far beyond the joint's limit
    assert robot.max_speed_rad_s * 0.01 < 0.5 < robot.upper_rad[JOINT] < 10.0
    servo = emulated.servo(robot.servo_ids[JOINT])
    goals: list[int] = []

    def on_the_bus(record: CycleRecord) -> None:
        goals.append(servo.peek("goal_position"))

    backend = ServoChainBackend(
        robot,
        port=url,
        port_handler_factory=EmulatedPortHandler,
        clock=lambda: emulated.now_s,
        sleep=emulated.advance,
    )
    with backend:
        records = play_commands(
            backend, table, 100.0, SafetyLayer.clip_only(robot), observers=[on_the_bus]
        )
    assert len(records) == len(table)  # the virtual clock is never late: one row per cycle
    sent = np.array([r.command_rad for r in records])
    np.testing.assert_array_equal(sent[:20], table[:20])
    np.testing.assert_array_equal(sent[20:, JOINT], robot.upper_rad[JOINT])
    converter = TickConverter.for_robot(robot)
    expected = [int(converter.clip_ticks(converter.to_ticks(row))[JOINT]) for row in sent]
    assert goals == expected
    assert goals[5] - goals[4] == expected[5] - expected[4] > 300  # 0.5 rad at 652 ticks/rad
    assert np.diff([r.time_s for r in records]) == pytest.approx(np.full(29, 0.01))


def test_play_returns_what_was_sent_and_measured_on_the_twin() -> None:
    robot = load_robot("snake8")
    with TwinBackend(robot) as twin:
        hold = twin.read_state().position_rad
        table = np.tile(hold, (40, 1))
        table[10:, 2] += 0.2
        time_s, sent, position, effort = play(twin, robot, table, 100.0)
    assert sent.shape == position.shape == effort.shape == table.shape
    np.testing.assert_array_equal(sent, table)
    np.testing.assert_allclose(np.diff(time_s), 0.01)
    assert position[-1, 2] - hold[2] > 0.1  # the servo followed the step


def test_an_excitation_record_logs_the_twin_body_like_a_run(tmp_path: Path) -> None:
    robot = load_robot("snake12")
    path = tmp_path / "lift.csv"
    with TwinBackend(robot) as twin:
        plan = chirp_plan(robot, twin.read_state().position_rad, 1, 0.5, duration_s=0.5)
        assert record(twin, robot, plan, path) == len(plan)
    log = read_log(path)
    np.testing.assert_array_equal(log.column("cycle"), np.arange(len(plan)))
    np.testing.assert_allclose(log.joints("command_rad"), plan, atol=1e-6)  # %.6g in the CSV
    assert np.isfinite(log.column("com_x_m")).all() and np.isfinite(log.column("imu_qw")).all()
