"""Twin-backed emulated servos obey their gain registers, written through the unmodified SDK."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

import dynamixel_sdk as dxl
import numpy as np
import pytest

from snakebot.config import RobotConfig, load_robot
from snakebot.config.schema import GainRegisters
from snakebot.emulation import EmulatedChain, registered
from snakebot.emulation.physics import TwinMotion, make_twin_chain
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.errors import ConfigError
from snakebot.gaits import make_gait
from snakebot.servo.dynamics import servo_dynamics
from snakebot.types import PDGains

BAUD = 1_000_000
XL430_FACTORY = GainRegisters(position_p=640, position_i=0, position_d=4000)


class Bus:
    """The stock SDK on an emulated chain, addressed by control-table names."""

    def __init__(self, chain: EmulatedChain, port: EmulatedPortHandler) -> None:
        self.chain, self.port = chain, port
        self.packet = dxl.PacketHandler(2.0)
        self.table = chain.servos[0].table

    def write(self, servo_id: int, key: str, value: int) -> None:
        register = self.table[key]
        send = {
            1: self.packet.write1ByteTxRx,
            2: self.packet.write2ByteTxRx,
            4: self.packet.write4ByteTxRx,
        }[register.size]
        result, error = send(self.port, servo_id, register.address, value)
        assert (result, error) == (dxl.COMM_SUCCESS, 0)

    def present(self, servo_id: int) -> int:
        ticks, result, _ = self.packet.read4ByteTxRx(
            self.port, servo_id, self.table["present_position"].address
        )
        assert result == dxl.COMM_SUCCESS
        return int(ticks)


@pytest.fixture
def robot() -> RobotConfig:
    # Config gains unlike the factory's: the twin must follow the registers, not the file.
    return dataclasses.replace(load_robot("snake8"), gains=PDGains(5.6, 0.0))


@pytest.fixture
def twin_bus(robot: RobotConfig) -> Iterator[tuple[Bus, TwinMotion]]:
    chain, motion = make_twin_chain(robot, BAUD)
    with registered(chain) as url:
        port = EmulatedPortHandler(url)
        assert port.openPort() and port.setBaudRate(BAUD)
        yield Bus(chain, port), motion
        port.closePort()


def actuator_gains(chain: EmulatedChain, motion: TwinMotion) -> tuple[np.ndarray, np.ndarray]:
    """The twin's position actuators' kp and kv, shape (N,), once the chain has stepped up to
    now (the twin takes up the registers when it next steps, as the chain steps lazily)."""
    chain.settle()
    model = motion.twin.model
    return model.actuator_gainprm[:, 0].copy(), -model.actuator_biasprm[:, 2].copy()


def expected(
    robot: RobotConfig, registers: GainRegisters, timestep_s: float
) -> tuple[float, float]:
    """The twin's kp and kv for gain registers, through the servo's register -> SI mapping."""
    servo = servo_dynamics(robot.servo.physics, robot.servo.gains_of(registers))
    return servo.stiffness_nm_per_rad, servo.actuator_kv(timestep_s)


def step_errors(bus: Bus, p_gains: dict[int, int], step_ticks: int, after_s: float) -> list[int]:
    """Give servos their P gains, torque on, step their goals; goal - present after ``after_s``."""
    for servo_id, p in p_gains.items():
        bus.write(servo_id, "position_p_gain", p)
    for servo_id in range(1, 9):
        bus.write(servo_id, "torque_enable", 1)
    goals = {servo_id: bus.present(servo_id) + step_ticks for servo_id in p_gains}
    for servo_id, goal in goals.items():
        bus.write(servo_id, "goal_position", goal)
    bus.chain.advance(after_s)
    return [goal - bus.present(servo_id) for servo_id, goal in goals.items()]


def test_the_twin_starts_with_the_factory_gains_of_the_registers(
    robot: RobotConfig, twin_bus: tuple[Bus, TwinMotion]
) -> None:
    bus, motion = twin_bus
    kp, _ = actuator_gains(bus.chain, motion)
    assert np.all(kp == 0.0)  # factory Torque Enable is off: limp
    for servo_id in range(1, 9):
        bus.write(servo_id, "torque_enable", 1)
    kp, kv = actuator_gains(bus.chain, motion)
    factory = expected(robot, XL430_FACTORY, float(motion.twin.model.opt.timestep))
    assert kp == pytest.approx(np.full(8, factory[0]))
    assert kv == pytest.approx(np.full(8, factory[1]))


def test_a_low_position_p_gain_tracks_a_step_worse_than_a_high_one(
    twin_bus: tuple[Bus, TwinMotion],
) -> None:
    bus, _ = twin_bus
    # Joints 1 and 6 (IDs 2 and 7) mirror each other in the 8-joint chain.
    low, high = step_errors(bus, {2: 100, 7: 2000}, step_ticks=200, after_s=0.2)
    assert low > 150 and high < 30


def test_equal_gains_on_mirrored_joints_track_alike(twin_bus: tuple[Bus, TwinMotion]) -> None:
    bus, _ = twin_bus
    first, second = step_errors(bus, {2: 640, 7: 640}, step_ticks=200, after_s=0.2)
    assert abs(first - second) <= 5 and 30 < first < 150


def test_gains_written_with_torque_off_wait_and_position_i_is_ignored(
    robot: RobotConfig, twin_bus: tuple[Bus, TwinMotion]
) -> None:
    bus, motion = twin_bus
    timestep = float(motion.twin.model.opt.timestep)
    bus.write(3, "position_p_gain", 1200)
    bus.write(3, "position_d_gain", 100)
    kp, kv = actuator_gains(bus.chain, motion)
    assert kp[2] == 0.0 and kv[2] == 0.0  # the joint stays limp until its torque comes on
    bus.write(3, "torque_enable", 1)
    kp, kv = actuator_gains(bus.chain, motion)
    assert (kp[2], kv[2]) == pytest.approx(expected(robot, GainRegisters(1200, 0, 100), timestep))
    assert kp[1] == 0.0  # torque still off there
    bus.write(3, "position_i_gain", 500)  # the twin's loop is PD: no I term
    kp_after, kv_after = actuator_gains(bus.chain, motion)
    assert kp_after[2] == kp[2] and kv_after[2] == kv[2]


def test_an_ax_twin_takes_its_stiffness_from_the_compliance_slope_registers() -> None:
    robot = load_robot("snake12-ax12a")
    chain, motion = make_twin_chain(robot, BAUD)
    packet = dxl.PacketHandler(1.0)
    table = chain.servos[0].table
    with registered(chain) as url:
        port = EmulatedPortHandler(url)
        assert port.openPort() and port.setBaudRate(BAUD)

        def write(servo_id: int, key: str, value: int) -> None:
            send = packet.write1ByteTxRx if table[key].size == 1 else packet.write2ByteTxRx
            assert send(port, servo_id, table[key].address, value) == (dxl.COMM_SUCCESS, 0)

        for servo_id in robot.servo_ids:
            write(servo_id, "torque_enable", 1)
        factory = actuator_gains(chain, motion)[0]
        write(3, "cw_compliance_slope", 16)
        write(3, "ccw_compliance_slope", 16)
        port.closePort()
    kp = actuator_gains(chain, motion)[0]
    stiff = robot.servo.gains_from({"cw_compliance_slope": 16, "ccw_compliance_slope": 16})
    assert factory == pytest.approx(np.full(12, robot.gains.kp_nm_per_rad))  # slope 32
    assert kp[2] == pytest.approx(stiff.kp_nm_per_rad) == pytest.approx(2 * factory[2])
    assert np.all(np.delete(kp, 2) == np.delete(factory, 2))


def _xm430_twin_bus(**ground: object) -> tuple[EmulatedChain, TwinMotion]:
    robot = load_robot("snake8-xm430")
    return make_twin_chain(robot, BAUD, **ground)  # type: ignore[arg-type]


def test_goal_current_in_current_based_position_caps_the_twins_torque() -> None:
    """Operating Mode 5 written through the SDK: Goal Current caps the joint's push at
    kt * |Goal Current|, and the joint still turns towards its goal; mode 3 pushes as it
    always did."""
    chain, motion = _xm430_twin_bus()
    robot = motion.robot
    stall = robot.servo.physics.stall_torque_nm
    table = chain.servos[0].table
    kt = stall / table.specs.stall_current_a
    with registered(chain) as url:
        port = EmulatedPortHandler(url)
        assert port.openPort() and port.setBaudRate(BAUD)
        bus = Bus(chain, port)
        for servo_id in (2, 7):
            bus.write(servo_id, "operating_mode", 5)  # EEPROM: torque still off
        cap_ticks = round(0.3 / kt / table["goal_current"].scale)
        bus.write(2, "goal_current", cap_ticks)  # 0.3 N*m on joint 1; joint 6 at its limit
        errors = step_errors(bus, {2: 800, 7: 800}, step_ticks=300, after_s=0.05)
        state = motion.twin.read_state()
        port.closePort()
    capped, full = abs(state.effort_nm[1]), abs(state.effort_nm[6])
    assert capped <= 1.05 * cap_ticks * table["goal_current"].scale * kt, state.effort_nm
    assert full > 2 * capped, state.effort_nm
    assert 0 < errors[1] < errors[0] < 300  # the capped joint lags, yet moves


def test_the_twin_under_the_bus_stands_on_the_terrain_asked_for() -> None:
    _chain, motion = _xm430_twin_bus(terrain="pegs:density=100,seed=1")
    assert motion.twin.terrain is not None and motion.twin.terrain.name == "pegs"
    assert motion.twin.model.ngeom > _xm430_twin_bus()[1].twin.model.ngeom  # the pegs are there


def test_a_wrapped_start_boots_the_servos_holding_the_coil_on_the_pole() -> None:
    robot = load_robot("snake12")
    gait = make_gait("rolling_helix", robot.joint_count, {"pole_radius_m": 0.052})
    pose = gait.targets(0.0)
    chain, motion = make_twin_chain(robot, BAUD, terrain="pole", wrapped_pose_rad=pose)
    start = motion.twin.body_state().com_m[2]
    assert start > 0.1  # coiled up the pole, not lying beside it
    assert all(s.torque_enabled for s in chain.servos)
    assert [s.peek("goal_position") for s in chain.servos] == [
        s.peek("present_position") for s in chain.servos
    ]
    chain.advance(1.0)
    assert motion.twin.body_state().com_m[2] > start - 0.02  # held there, not slumping off
    with pytest.raises(ConfigError, match="pole"):
        make_twin_chain(robot, BAUD, wrapped_pose_rad=pose)  # no pole on the flat floor
