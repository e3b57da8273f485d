"""The fuller servo model (issue 12 item 5): each part optional, off by default, and when on,
what a user of the real robot would see."""

from __future__ import annotations

import math
from pathlib import Path

import dynamixel_sdk as dxl
import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.config import RobotConfig, load_robot
from snakebot.emulation import registered
from snakebot.emulation.physics import make_twin_chain
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.errors import ConfigError, ServoFaultError
from snakebot.servo.dynamics import servo_dynamics
from snakebot.telemetry import read_log
from snakebot.types import JointCommand

FOLD = np.array([0, 1.5, 1.5, 1.5, 1.5, 1.5, 0, 0])  # presses modules 2..5 into each other


def robot_with(config_dir: Path, servo: str = "", robot: str = "") -> RobotConfig:
    """snake8 with lines added to its servo file's [twin] and its own [twin.servo]."""
    if servo:
        path = config_dir / "servos" / "xl430-w250.toml"
        path.write_text(path.read_text() + f"\n[twin]\n{servo}\n")
    path = config_dir / "robots" / "snake8.toml"
    if robot:
        text = path.read_text().replace(
            "[joint_defaults]", f"[twin.servo]\n{robot}\n\n[joint_defaults]", 1
        )
        path.write_text(text)
    return load_robot(path)


def hold(twin: TwinBackend, pose: np.ndarray, seconds: float, dt: float = 0.01) -> None:
    """Go to ``pose`` over the first second, as the safety ramp would, and hold it."""
    for k in range(round(seconds / dt)):
        twin.send_command(JointCommand(pose * min(1.0, k * dt)))
        twin.advance(dt)


def test_without_the_new_parts_the_twin_reports_no_electrics_and_reads_exact_positions() -> None:
    with TwinBackend(load_robot("snake8")) as twin:
        hold(twin, np.full(8, 0.2), 0.5)
        state = twin.read_state()
        assert np.array_equal(state.position_rad, twin.data.qpos[twin._qpos_index])
        physics = twin.physics_health()
    assert physics is not None and "electrical_energy_j" not in physics


def stiffness(robot: RobotConfig) -> float:
    """The twin's joint stiffness (N·m/rad) at the robot's [gains]."""
    return servo_dynamics(robot.servo.physics, robot.gains).stiffness_nm_per_rad


def test_the_p_gain_divisor_has_one_home_the_servo_files_physics(config_dir: Path) -> None:
    shipped = load_robot("snake8")
    path = config_dir / "servos" / "xl430-w250.toml"
    path.write_text(path.read_text().replace("p_gain_divisor = 256", "p_gain_divisor = 128"))
    robot = load_robot(config_dir / "robots" / "snake8.toml")
    assert robot.servo.physics.p_gain_divisor == 128.0
    # The same registers (P = 640) mean twice the stiffness, for the twin and the bus alike.
    assert robot.gains.kp_nm_per_rad == pytest.approx(2 * shipped.gains.kp_nm_per_rad)
    assert stiffness(robot) == pytest.approx(2 * stiffness(shipped))
    assert robot.gain_registers == shipped.gain_registers
    # A second key in the servo file's [twin] would be a second home: refused, pointing at it.
    path.write_text(path.read_text() + "\n[twin]\np_gain_divisor = 200\n")
    with pytest.raises(
        ConfigError,
        match=r"xl430-w250.toml: twin.p_gain_divisor: the P-gain "
        r"divisor is physics.p_gain_divisor",
    ):
        load_robot(config_dir / "robots" / "snake8.toml")


def test_a_robots_fitted_p_gain_divisor_changes_what_its_registers_mean(config_dir: Path) -> None:
    # What `snakebot sysid --params p_divisor` writes: [twin.servo] p_gain_divisor.
    shipped = load_robot("snake8")
    robot = robot_with(config_dir, robot="p_gain_divisor = 128")
    assert robot.servo.physics.p_gain_divisor == 128.0
    assert robot.servo.gain_mapping.p_gain_divisor == 128.0
    assert robot.gains.kp_nm_per_rad == pytest.approx(2 * shipped.gains.kp_nm_per_rad)
    assert robot.gains.kd_nms_per_rad == pytest.approx(shipped.gains.kd_nms_per_rad)
    with TwinBackend(robot) as twin:
        twin_kp = float(twin.model.actuator_gainprm[0, 0])
    assert twin_kp == pytest.approx(2 * stiffness(shipped))
    # The Dynamixel backend turns the SI gains back with the same mapping: the servos get the
    # robot file's registers, and the emulated twin behind them the same stiffness as the twin.
    from snakebot.backends.chain.backend import ServoChainBackend

    chain, motion = make_twin_chain(robot, 1_000_000)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    with (
        registered(chain) as url,
        ServoChainBackend(
            robot,
            port=url,
            baud=1_000_000,
            port_handler_factory=EmulatedPortHandler,
            clock=lambda: chain.now_s,
            sleep=chain.advance,
        ) as backend,
    ):
        assert backend.gain_registers == shipped.gain_registers
        backend.advance(0.02)
        chained_kp = motion.twin.model.actuator_gainprm[:, 0].copy()
    got = {
        (s.peek("position_p_gain"), s.peek("position_i_gain"), s.peek("position_d_gain"))
        for s in chain.servos
    }
    assert got == {(640, 0, 4000)}
    assert np.allclose(chained_kp, twin_kp)


def test_out_of_range_or_incomplete_parts_name_the_file_and_key(config_dir: Path) -> None:
    path = config_dir / "robots" / "snake8.toml"
    original = path.read_text()
    with pytest.raises(ConfigError, match=r"snake8.toml: twin.servo.p_gain_divisor: expected"):
        robot_with(config_dir, robot="p_gain_divisor = 0")
    path.write_text(original)
    with pytest.raises(ConfigError, match=r"xl430-w250.toml: twin.encoder_noise_rad: expected"):
        robot_with(config_dir, servo="encoder_noise_rad = 1")
    servo = config_dir / "servos" / "xl430-w250.toml"
    servo.write_text(servo.read_text().replace("\n[twin]\nencoder_noise_rad = 1\n", ""))
    with pytest.raises(
        ConfigError,
        match=r"snake8.toml: twin.servo.battery_resistance_ohm: "
        "battery sag needs the current draw",
    ):
        robot_with(config_dir, robot="battery_resistance_ohm = 0.5")


def test_current_draw_and_electrical_cost_of_transport(config_dir: Path) -> None:
    robot = robot_with(config_dir, servo="stall_current_a = 1.3")
    with TwinBackend(robot) as twin:
        hold(twin, FOLD, 3.0)  # two servos end up pushing at their 1.4 N·m limit
        stalled = twin.physics_health()
    assert stalled is not None
    # A servo at stall draws its datasheet stall current; the fold stalls at least two.
    assert stalled["peak_current_a"] > 2 * 0.9 * 1.3
    assert stalled["copper_loss_j"] > 0.9 * stalled["electrical_energy_j"]  # stalled: heat
    with TwinBackend(robot) as twin:
        from snakebot.gaits import make_gait

        gait = make_gait("serpenoid", 8)
        for k in range(500):
            twin.send_command(JointCommand(gait.targets(k * 0.01) * min(1.0, k / 100)))
            twin.advance(0.01)
        moving = twin.physics_health()
    assert moving is not None
    electrical = moving["electrical_energy_j"]
    assert isinstance(electrical, float) and moving["copper_loss_j"] > 0
    cot = moving["electrical_cost_of_transport"]
    assert isinstance(cot, float) and cot > 0
    assert electrical > moving["mechanical_energy_j"]  # the windings' heat comes on top


def test_battery_sag_lowers_the_torque_a_stalled_servo_gives(config_dir: Path) -> None:
    robot = robot_with(
        config_dir, servo="stall_current_a = 1.3", robot="battery_resistance_ohm = 1.0"
    )
    with TwinBackend(robot) as twin:
        hold(twin, FOLD, 3.0)
        physics = twin.physics_health()
        limit = float(twin.model.actuator_forcerange[:, 1].max())
    assert physics is not None
    assert physics["lowest_supply_voltage_v"] < 11.1 - 2.0
    assert limit < 1.4 * (11.1 - 2.0) / 11.1


def test_sustained_stall_trips_the_overload_protection(config_dir: Path) -> None:
    robot = robot_with(config_dir, robot="overload_trip_s = 1.0")
    with TwinBackend(robot) as twin, pytest.raises(ServoFaultError, match="Overload") as caught:
        hold(twin, FOLD, 5.0)
    assert caught.value.servo_id in (2, 3, 4, 5, 6)
    assert "tripped at t=" in str(caught.value)
    with TwinBackend(robot, raise_on_overload=False) as twin:
        hold(twin, FOLD, 5.0)
        tripped = twin.overloaded
        assert tripped.any()
        assert np.all(twin.model.actuator_gainprm[tripped, 0] == 0.0)  # limp, as the firmware


def test_the_emulator_latches_the_twins_overload_for_the_sdk(config_dir: Path) -> None:
    robot = robot_with(config_dir, robot="overload_trip_s = 1.0")
    chain, motion = make_twin_chain(robot, 1_000_000)
    table = chain.servos[0].table
    packet = dxl.PacketHandler(2.0)
    with registered(chain) as url:
        port = EmulatedPortHandler(url)
        assert port.openPort() and port.setBaudRate(1_000_000)
        for joint in robot.joints:
            packet.write1ByteTxRx(port, joint.servo_id, table["torque_enable"].address, 1)
        for joint, angle in zip(robot.joints, FOLD, strict=True):
            goal = 2048 + round(angle * 4096 / (2 * math.pi))
            packet.write4ByteTxRx(port, joint.servo_id, table["goal_position"].address, goal)
        chain.advance(4.0)
        errors = {}
        for joint in robot.joints:
            value, result, _ = packet.read1ByteTxRx(
                port, joint.servo_id, table["hardware_error_status"].address
            )
            assert result == dxl.COMM_SUCCESS
            errors[joint.servo_id] = value
        port.closePort()
    latched = [i for i, v in errors.items() if v & 0x20]
    assert latched and set(latched) <= {2, 3, 4, 5, 6}
    assert all(v == 0 for i, v in errors.items() if i not in latched)
    assert motion.twin.overloaded.sum() == len(latched)


def test_encoder_ticks_and_seeded_reading_noise(config_dir: Path) -> None:
    robot = robot_with(config_dir, robot="quantise_encoder = 1")
    tick = 2 * math.pi / 4096
    with TwinBackend(robot) as twin:
        hold(twin, np.full(8, 0.2), 0.3)
        read = twin.read_state().position_rad
    assert np.allclose(read / tick, np.round(read / tick), atol=1e-9)
    path = config_dir / "robots" / "snake8.toml"
    path.write_text(path.read_text().replace("quantise_encoder = 1", "encoder_noise_rad = 0.01"))
    noisy = load_robot(path)
    reads = []
    for seed in (1, 1, 2):
        with TwinBackend(noisy, seed=seed) as twin:
            hold(twin, np.zeros(8), 0.1)
            truth = twin.data.qpos[twin._qpos_index].copy()
            reads.append(np.array([twin.read_state().position_rad - truth for _ in range(200)]))
    assert np.array_equal(reads[0], reads[1]) and not np.array_equal(reads[0], reads[2])
    assert reads[0].std() == pytest.approx(0.01, rel=0.1)


def test_the_head_imu_sees_a_roll_and_is_logged(tmp_path: Path) -> None:
    from snakebot.cli.main import main

    log = tmp_path / "roll.csv"
    assert (
        main(
            ["run", "--robot", "snake12", "--gait", "rolling", "--duration", "6", "--log", str(log)]
        )
        == 0
    )
    telemetry = read_log(log)
    roll_rate = telemetry.column("gyro_x_rad_s")
    assert np.abs(roll_rate).max() > 1.0  # the head spins about its own axis
    quat = np.stack([telemetry.column(f"imu_q{c}") for c in "wxyz"], axis=1)
    assert np.allclose(np.linalg.norm(quat, axis=1), 1.0, atol=1e-4)
    with TwinBackend(load_robot("snake8")) as twin:
        hold(twin, np.zeros(8), 0.5)
        body = twin.body_state()
    assert body.head_gyro_rad_s is not None and np.abs(body.head_gyro_rad_s).max() < 0.05


def test_batched_tuning_says_it_leaves_out_sag_and_overload(config_dir: Path) -> None:
    from snakebot.tuning.engine import TwinBatch

    robot = robot_with(config_dir, robot="overload_trip_s = 1.0")
    with pytest.warns(UserWarning, match="batched tuning and sysid replays leave them out"):
        TwinBatch(robot)
