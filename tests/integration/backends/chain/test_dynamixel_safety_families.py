"""The safety guarantees on every servo family, through the real dynamixel_sdk and the emulator.

Each test runs once per family bench (``FAMILIES``): X-series on Protocol 2.0 (Fast Sync Read,
Bus Watchdog), X-series switched to Protocol 1.0 (Bulk Read; its watchdog and Hardware Error
Status registers sit below address 256, so it keeps them), and the models without a watchdog or
Hardware Error Status: AX-12A (no group read: one Read per servo), MX-28 with its Protocol 1.0
firmware (Bulk Read) and the Feetech STS3215 (SYNC_READ through scservo_sdk, no watchdog, no
hardware error register: its status byte's bits) and the SCS0009 (big-endian words, no Sync
Read: one Read per servo).
A failed connect ends in the stop policy, a second Ctrl-C during the stop ramp too, a joint found
outside its limits comes in at the slew limit, and a port that vanishes is a BusError saying what
the servos do now.
"""

from __future__ import annotations

import dataclasses
import errno
import shutil
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.backends.chain.faults import HardwareFaultError, ServoSettingsError
from snakebot.config import load_robot
from snakebot.config.schema import RobotConfig
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.emulation import EmulatedChain, make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.emulation.port_feetech import EmulatedScsPortHandler
from snakebot.errors import BusError
from snakebot.gaits import make_gait
from snakebot.types import JointCommand
from tests.conftest import CONFIGS
from tests.integration.backends.chain.conftest import BAUD, ChainWatcher, robot_variant


@dataclass(frozen=True)
class Family:
    """How to build one family's bench: the chain's model and protocol, the robot's."""

    name: str
    model: str
    protocol: float
    robot: Callable[..., RobotConfig]

    def chain(self, ids: tuple[int, ...]) -> EmulatedChain:
        chain = make_chain_for_ids(self.model, ids, baud=BAUD)
        for servo in chain.servos:
            servo.poke("return_delay_time", 0)
            if servo.memory.has("protocol_type"):
                servo.poke("protocol_type", 1 if self.protocol == 1.0 else 2)
        return chain


def x_series(protocol: float) -> Callable[..., RobotConfig]:
    def robot(folder: Path, **safety: Any) -> RobotConfig:
        base = robot_variant("snake12", **safety)
        return dataclasses.replace(base, bus=dataclasses.replace(base.bus, protocol=protocol))

    return robot


def shipped(name: str) -> Callable[..., RobotConfig]:
    def robot(folder: Path, **safety: Any) -> RobotConfig:
        return robot_variant(name, **safety)

    return robot


MX28_ROBOT = """name = "snake12-mx28"
servo = "MX-28"

[bus]
port = "/dev/ttyUSB0"
baud = 1000000
protocol = 1.0

[link]
length_m = 0.07
radius_m = 0.025
mass_kg = 0.1

[gains]
position_p = 32

[safety]
ramp_s = 1.0
max_speed_fraction = 0.9
stop_policy = "hold"

[twin]
timestep_s = 0.002
ground = "isotropic"
axial_friction = 0.7
lateral_friction = 0.7

[joint_defaults]
zero_offset_rad = 0.0
direction = 1
lower_rad = -1.5
upper_rad = 1.5
""" + "".join(
    f'\n[[joints]]\nservo_id = {i}\naxis = "{("yaw", "pitch")[(i - 1) % 2]}"\n'
    for i in range(1, 13)
)


def mx28(folder: Path, **safety: Any) -> RobotConfig:
    """A 12-joint MX-28 (Protocol 1.0 firmware) snake: a robot file beside a copy of the shipped
    servo files in ``folder`` (no MX-28 robot ships; its servo file does)."""
    path = folder / "robots" / "snake12-mx28.toml"
    if not path.exists():
        path.parent.mkdir(parents=True)
        shutil.copytree(CONFIGS / "servos", folder / "servos")
        path.write_text(MX28_ROBOT)
    base = load_robot(path)
    return dataclasses.replace(base, safety=dataclasses.replace(base.safety, **safety))


def scs0009(folder: Path, **safety: Any) -> RobotConfig:
    """A 12-joint SCS0009 snake (big-endian words, one Read per servo, P/D without I): the
    shipped STS3215 snake with its servo swapped, at the SCS0009's factory gains."""
    path = folder / "robots" / "snake12-scs0009.toml"
    if not path.exists():
        path.parent.mkdir(parents=True)
        shutil.copytree(CONFIGS / "servos", folder / "servos")
        text = (CONFIGS / "robots" / "snake12-sts3215.toml").read_text()
        path.write_text(
            text.replace('servo = "STS3215"', 'servo = "SCS0009"')
            .replace('name = "snake12-sts3215"', 'name = "snake12-scs0009"')
            .replace("[gains]", "")
            .replace("position_p = 32\nposition_i = 0\nposition_d = 32\n", "")
        )
    base = load_robot(path)
    return dataclasses.replace(base, safety=dataclasses.replace(base.safety, **safety))


FAMILIES = [
    Family("x-p2", "XL430-W250", 2.0, x_series(2.0)),
    Family("x-p1", "XL430-W250", 1.0, x_series(1.0)),
    Family("ax12a", "AX-12A", 1.0, shipped("snake12-ax12a")),
    Family("mx28", "MX-28", 1.0, mx28),
    Family("sts3215", "STS3215", 0.0, shipped("snake12-sts3215")),
    Family("scs0009", "SCS0009", 1.0, scs0009),
]
# The vendor SDK's port handler that opens the emulator's dxlemu:// URL.
HANDLERS = {"dynamixel": EmulatedPortHandler, "feetech": EmulatedScsPortHandler}


@dataclass
class FamilyBench:
    family: Family
    chain: EmulatedChain
    url: str
    folder: Path

    def robot(self, **safety: Any) -> RobotConfig:
        return self.family.robot(self.folder, **safety)

    def backend(self, robot: RobotConfig, **kwargs: Any) -> ServoChainBackend:
        chain = self.chain
        options: dict[str, Any] = {
            "clock": lambda: chain.now_s,
            "sleep": chain.advance,
            "port_handler_factory": HANDLERS[chain.servos[0].vendor],
        }
        options.update(kwargs)
        return ServoChainBackend(robot, port=self.url, baud=BAUD, **options)


@pytest.fixture(params=FAMILIES, ids=[f.name for f in FAMILIES])
def fbench(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[FamilyBench]:
    family: Family = request.param
    chain = family.chain(tuple(range(1, 13)))
    with registered(chain) as url:
        yield FamilyBench(family, chain, url, tmp_path)


def assert_left_per_policy(
    bench: FamilyBench, backend: ServoChainBackend, policy: str, skip: tuple[int, ...] = ()
) -> None:
    """Torque as the policy says on every answering servo, a watchdog (where there is one)
    disarmed, and so still a second of bus silence later."""
    servos = [s for s in bench.chain.servos if s.servo_id not in skip]
    watchdog = backend.capabilities.bus_watchdog
    for servo in servos:
        assert servo.torque_enabled == (policy == "hold"), servo.servo_id
        if watchdog:
            assert servo.peek("bus_watchdog") == 0, servo.servo_id
    bench.chain.advance(1.0)
    for servo in servos:
        assert servo.torque_enabled == (policy == "hold"), servo.servo_id


# What each vendor's datasheet calls the register that turns torque off on a fault.
SHUTDOWN_REGISTER = {"feetech": "Unload Condition", "dynamixel": "Alarm Shutdown"}


def test_a_shutdown_without_overload_and_overheat_refuses_to_connect(
    fbench: FamilyBench,
) -> None:
    """With no Bus Watchdog, the shutdown register is all that protects a stalled servo once
    the host dies: connect refuses one lacking the overload or overheating bit, naming the
    register as the servo's datasheet does."""
    if fbench.family.name.startswith("x-"):
        pytest.skip("X series: its Bus Watchdog guards it, the Shutdown bits are not required")
    fbench.chain.servo(4).poke("shutdown", 0x04)  # overheating only
    backend = fbench.backend(fbench.robot())
    with pytest.raises(ServoSettingsError) as info:
        backend.connect()
    name = SHUTDOWN_REGISTER[fbench.chain.servos[0].vendor]
    assert info.value.problems[0].startswith(f"servo 4: {name} is 4, needs bits 2 and 5")
    assert not any(s.torque_enabled for s in fbench.chain.servos)


def test_each_family_reads_by_its_own_method(fbench: FamilyBench) -> None:
    backend = fbench.backend(fbench.robot(ramp_s=0.2))
    expected = {
        "x-p2": "fast_sync_read",
        "x-p1": "bulk_read",
        "ax12a": "read",
        "mx28": "bulk_read",
        "sts3215": "sync_read",
        "scs0009": "read",
    }[fbench.family.name]
    assert backend.bus.capabilities.read_method == expected
    with backend:
        state = backend.read_state()
        assert backend.fast_read == (expected == "fast_sync_read")
        assert backend.bus.group_fallbacks == 0
    assert np.allclose(state.position_rad, 0.0, atol=0.01)


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_a_servo_lost_right_after_torque_on_fails_connect_with_the_policy_applied(
    fbench: FamilyBench, policy: str
) -> None:
    def watch(chain: EmulatedChain) -> None:
        servo = chain.servo(7)
        if servo.torque_enabled and not chain.faults_of(servo).silent:
            chain.silence(7)

    fbench.chain.physics = ChainWatcher(fbench.chain, watch)
    backend = fbench.backend(fbench.robot(ramp_s=0.2, stop_policy=policy))
    with pytest.raises(BusError) as info:
        backend.connect()
    assert 7 in info.value.servo_ids
    assert not backend.bus.is_open
    fbench.chain.physics = None
    assert_left_per_policy(fbench, backend, policy, skip=(7,))


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_a_second_ctrl_c_during_the_stop_ramp_still_ends_in_the_policy(
    fbench: FamilyBench, policy: str
) -> None:
    chain = fbench.chain
    sleeps: list[int] = []
    triggers: set[int] = set()

    def sleep(dt: float) -> None:
        sleeps.append(len(sleeps) + 1)
        if len(sleeps) in triggers:
            raise KeyboardInterrupt
        chain.advance(dt)

    backend = fbench.backend(fbench.robot(ramp_s=1.0, stop_policy=policy), sleep=sleep)
    backend.connect()
    for _ in range(150):
        backend.send_command(JointCommand(np.linspace(-0.8, 0.8, 12)))
        backend.advance(0.01)
    triggers.update({len(sleeps) + 10, len(sleeps) + 12})
    with pytest.raises(KeyboardInterrupt):
        backend.close()
    assert not backend.bus.is_open
    assert len(sleeps) > max(triggers) - 12  # the ramp had begun when the signals came
    assert_left_per_policy(fbench, backend, policy)


def test_a_joint_found_outside_its_limits_is_brought_in_at_the_slew_limit(
    fbench: FamilyBench,
) -> None:
    robot = fbench.robot(ramp_s=0.5)
    ticks = robot.servo.physics.ticks
    servo = fbench.chain.servo(3)
    servo.state = dataclasses.replace(servo.state, position_rad=2.5)
    servo.poke("goal_position", ticks.centre)  # a stale goal it must not jump to either
    goals: list[int] = []
    with fbench.backend(robot) as backend:
        goals.append(servo.peek("goal_position"))  # Goal = Present at torque on
        run_gait(
            backend,
            make_gait("serpenoid", 12),
            SafetyLayer.for_robot(robot),
            RunPlan(duration_s=1.0),
            RunMetrics(12, robot.body_length_m, robot.total_mass_kg),
            on_cycle=lambda cycle, t: goals.append(servo.peek("goal_position")),
        )
    angles = (np.array(goals) - ticks.centre) * ticks.rad_per_tick
    assert abs(angles[0] - 2.5) < 2 * ticks.rad_per_tick
    step_limit = robot.max_speed_rad_s * 0.01 + ticks.rad_per_tick  # one 100 Hz cycle, a tick
    assert np.max(np.abs(np.diff(angles))) <= step_limit
    inside = int(np.argmax(angles <= 1.5))
    assert inside > 0 and np.all(np.diff(angles[: inside + 1]) <= 0)  # straight in, never out
    assert np.all(angles[inside:] <= 1.5 + 1e-9)


class UnpluggablePort(EmulatedPortHandler):  # type: ignore[misc]
    """The emulator's port handler whose device disappears when ``unplugged`` is set: every
    read and write raises the OSError (EIO) the OS gives for a vanished USB adapter."""

    unplugged = False

    def writePort(self, packet: list[int]) -> int:  # noqa: N802
        if UnpluggablePort.unplugged:
            raise OSError(errno.EIO, "Input/output error")
        return int(super().writePort(packet))

    def readPort(self, length: int) -> bytes:  # noqa: N802
        if UnpluggablePort.unplugged:
            raise OSError(errno.EIO, "Input/output error")
        return bytes(super().readPort(length))


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_the_port_vanishing_mid_run_is_a_bus_error_saying_what_the_servos_do(
    fbench: FamilyBench, policy: str
) -> None:
    UnpluggablePort.unplugged = False
    robot = fbench.robot(ramp_s=0.2, stop_policy=policy)
    backend = fbench.backend(robot, port_handler_factory=UnpluggablePort)
    backend.connect()

    def cycle() -> None:
        backend.send_command(JointCommand(np.full(12, 0.3)))
        backend.advance(0.01)
        backend.read_state()

    try:
        for _ in range(30):
            cycle()
        UnpluggablePort.unplugged = True
        with pytest.raises(BusError, match="the serial port vanished"):
            cycle()
        with pytest.raises(BusError) as info:
            backend.close()
    finally:
        UnpluggablePort.unplugged = False
    text = str(info.value)
    assert f"the stop policy ({policy}) could not be sent" in text
    if backend.capabilities.bus_watchdog:
        assert "Bus Watchdog tripped" in text
        fbench.chain.advance(1.0)
        assert all(s.watchdog_tripped for s in fbench.chain.servos)
    else:
        assert "no Bus Watchdog" in text  # and the shutdown register by its datasheet name
        assert SHUTDOWN_REGISTER[fbench.chain.servos[0].vendor] in text
        fbench.chain.advance(1.0)
        assert all(s.torque_enabled for s in fbench.chain.servos)  # what the text says


def test_an_overload_mid_run_stops_it_naming_the_servo(fbench: FamilyBench) -> None:
    """Hardware Error Status where the model has it, else the status byte's overload bit (a Bulk
    Read hides it: one servo per slow check is read alone, so all are seen within 12 checks)."""
    backend = fbench.backend(fbench.robot(ramp_s=0.2))
    backend.connect()
    try:
        for _ in range(20):
            backend.send_command(JointCommand(np.full(12, 0.2)))
            backend.advance(0.01)
            backend.read_state()
        fbench.chain.servo(5).latch_error(0x20)  # overload: torque off (Shutdown / Alarm Shutdown)
        with pytest.raises(HardwareFaultError) as info:
            for _ in range(12 * backend.slow_every + 1):
                backend.send_command(JointCommand(np.full(12, 0.2)))
                backend.advance(0.01)
                backend.read_state()
    finally:
        backend.close()
    assert info.value.servo_id == 5 and "overload" in info.value.flags
    if backend.capabilities.reboot:
        assert "snakebot servo reboot" in str(info.value)
    else:
        assert f"power-cycle it ({backend.bus.family.name} has no Reboot)" in str(info.value)


def test_a_servo_in_overload_at_connect_refuses_it(fbench: FamilyBench) -> None:
    fbench.chain.servo(4).latch_error(0x20)
    backend = fbench.backend(fbench.robot(ramp_s=0.2))
    with pytest.raises(HardwareFaultError) as info:
        backend.connect()
    assert info.value.servo_id == 4 and "overload" in info.value.flags
    assert not any(s.torque_enabled for s in fbench.chain.servos)
