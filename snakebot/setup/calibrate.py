"""Zero offsets from a straight snake, written into the robot file (``joints[].zero_offset_rad``).

The Dynamixel convention (snakebot.servo.ticks, the chain backend's): the offset lives in the
robot config; the servo's Homing Offset stays 0 and its Drive Mode reverse bit clear (the settings
say so and ``config diff`` checks it). An AX has neither register: its offset can only live in the
robot file. With every joint straight (0 rad), a servo reading ``ticks`` gets ``zero_offset_rad =
direction * (ticks - centre) * 2 pi / ticks`` (centre 2048 of 4096 on the X series, 512 of 1024 on
an AX).

A family that zeroes the servo itself (:attr:`ServoFamily.calibrates_homing_offset`, Feetech STS)
gets its Homing Offset written instead, so the straight joint reads the centre tick and the 0/4095
wrap lies behind the joint, where no goal or angle limit reaches. The firmware's rule is Present =
Actual - Offset, the offset sign-magnitude with its sign in bit 11 (±2047 ticks; the model data's
``homing_offset`` register encodes it). The actual position is what the servo reads plus the
offset it holds now, so a servo calibrated before (by snakebot or another tool) is measured right
and calibrating twice gives the same offsets (the sum taken modulo one turn, whether or not the
firmware wraps Present into 0..4095). The offset is clamped to the register's range, so no write
can exceed it (huggingface/lerobot#1296's "Magnitude 2114 exceeds 2047"); what it cannot hold (an
actual position of 0 wants -2048) is left to ``zero_offset_rad``. A servo whose positions leave
one turn (Feetech Phase bit 4, multi-turn feedback: huggingface/lerobot#1296) is refused, naming
the bit.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from snakebot.backends.chain.checks import check_settings, current_position_mode, shutdown_name
from snakebot.backends.chain.ticks import TickConverter
from snakebot.config import load_robot
from snakebot.config.schema import JointConfig, RobotConfig
from snakebot.errors import ConfigError, OutputError
from snakebot.servo.ticks import TickModel, ticks_to_rad
from snakebot.setup.diff import condition_note
from snakebot.setup.errors import SetupError, VerifyError
from snakebot.setup.link import Link
from snakebot.setup.settings import ChainSettings, has_watchdog
from snakebot.setup.toml_edit import format_float, set_in_joints, write_atomic

MAX_OFFSET_DEG = 20.0
_PREREQUISITES = ("operating_mode", "drive_mode", "homing_offset")
MOVED_TICKS = 8
"""How far (ticks, about 0.7 deg on 4096) a servo may read from its expected position after its
Homing Offset is written before calibrate says the joint moved."""
MULTI_TURN_BIT = 0x10
"""Feetech Phase (18) bit 4: full-angle (multi-turn) position feedback (memory-sts.md)."""


@dataclass(frozen=True)
class JointZero:
    """One joint's measurement: the servo's present ticks and the old and new zero offsets.

    Where calibrate writes the servo's Homing Offset, ``homing_offset`` is the value it writes
    (ticks; Present = Actual - Offset), ``old_homing_offset`` the one the servo held,
    ``actual_ticks`` its position before any offset and ``servo_angle_rad`` how far the servo's
    centre lies from the straight joint; elsewhere they are None.
    """

    joint: int
    servo_id: int
    present_ticks: int
    old_offset_rad: float
    new_offset_rad: float
    homing_offset: int | None = None
    old_homing_offset: int | None = None
    actual_ticks: int | None = None
    servo_angle_rad: float | None = None

    @property
    def angle_rad(self) -> float:
        """How far the servo's own centre lies from the straight joint (rad): the zero offset
        and, where it is written, the Homing Offset together."""
        return self.new_offset_rad if self.servo_angle_rad is None else self.servo_angle_rad


def zero_offset_rad(ticks: int, direction: int, model: TickModel) -> float:
    """The zero offset that makes a servo reading ``ticks`` report 0 rad: the angle the tick
    means with no offset (snakebot.servo.ticks)."""
    return ticks_to_rad(ticks, ticks=model, direction=direction)


def zeroes_servo(link: Link) -> bool:
    """Whether calibrate writes the servos' Homing Offset on this link (its family zeroes the
    servo itself and the model has the register) rather than leaving it 0."""
    return link.family.calibrates_homing_offset and "homing_offset" in link.bus.table


def measure(link: Link, chain: ChainSettings) -> list[JointZero]:
    """Read every servo's position (at the robot's baud) and compute the zero offsets (and the
    Homing Offsets, where :func:`zeroes_servo`). SetupError naming the servo and what to do when
    a servo is missing, lacks its settings or reads positions no offset can centre."""
    robot = chain.robot
    bus = link.at(chain.baud)
    missing = [i for i in robot.servo_ids if i not in bus.ping_all(robot.servo_ids)]
    if missing:
        raise SetupError(
            f"{link.port}: servo(s) {', '.join(map(str, missing))} do not answer at {chain.baud} "
            f"baud; run `snakebot config diff --robot {robot.name} --port {link.port}` first"
        )
    in_servo = zeroes_servo(link)
    wrong = []
    prerequisites = [
        k
        for k in _PREREQUISITES
        if k in bus.table and not (in_servo and k == "homing_offset")  # an AX has none of them
    ]
    for servo in chain.servos:
        values = bus.read_block(servo.servo_id, prerequisites) if prerequisites else {}
        for key in prerequisites:
            if key in {s.key for s in servo.settings} and values[key] != servo.get(key).raw:
                wrong.append(f"servo {servo.servo_id} {key} is {values[key]}")
    if wrong:
        raise SetupError(
            f"{link.port}: calibration needs the configured settings first ({'; '.join(wrong)}): "
            f"run `snakebot config apply --robot {robot.name} --port {link.port}`"
        )
    if link.family.capabilities(bus.table).sync_read:
        ticks = bus.sync_read("present_position", robot.servo_ids)
    else:  # no Sync Read: one Read per servo is quick enough once
        ticks = {i: bus.read_block(i, ("present_position",)) for i in robot.servo_ids}
    if not link.family.capabilities(bus.table).hardware_error_status:
        faulted = [(i, b) for i, b in sorted(bus.conditions.items()) if i in robot.servo_ids and b]
        if faulted:
            raise SetupError(
                f"{link.port}: calibration refused, nothing written: "
                + "; ".join(condition_note(link, i, b) for i, b in faulted)
            )
    tpr = robot.servo.physics.ticks
    zeros = []
    for index, joint in enumerate(robot.joints):
        present = ticks[joint.servo_id]["present_position"]
        if in_servo:
            zeros.append(_servo_zero(link, index, joint, present, tpr))
            continue
        offset = zero_offset_rad(present, joint.direction, tpr)
        zeros.append(JointZero(index, joint.servo_id, present, joint.zero_offset_rad, offset))
    return zeros


def _servo_zero(
    link: Link, index: int, joint: JointConfig, present: int, tpr: TickModel
) -> JointZero:
    """One joint zeroed in its servo: the Homing Offset that centres it, the rest in rad."""
    bus, servo_id, direction = link.bus, joint.servo_id, joint.direction
    if "phase" in bus.table:
        phase = bus.read(servo_id, "phase")
        if phase & MULTI_TURN_BIT:
            raise SetupError(
                f"{link.port}: servo {servo_id} has Phase (address "
                f"{bus.table['phase'].address}) bit 4 set, multi-turn position feedback: its "
                f"positions leave 0..{tpr.count - 1} and no Homing Offset centres them "
                f"(huggingface/lerobot#1296). Clear the bit (Phase {phase & ~MULTI_TURN_BIT}) in "
                "the servo settings and apply them, then calibrate"
            )
    register = bus.table["homing_offset"]
    old = bus.read(servo_id, "homing_offset")
    # Present = Actual - Offset, within one turn: whether the firmware wraps the difference into
    # 0..4095 or lets it go negative, modulo one turn gives the actual position back.
    actual = (present + old) % tpr.count
    wanted = actual - tpr.centre
    offset = min(max(wanted, register.minimum), register.maximum)
    rest = zero_offset_rad(actual - offset, direction, tpr)  # 0 unless the register ran out
    angle = zero_offset_rad(actual, direction, tpr)
    return JointZero(
        index, servo_id, present, joint.zero_offset_rad, rest, offset, old, actual, angle
    )


def with_offsets(robot: RobotConfig, offsets: Sequence[float]) -> RobotConfig:
    """``robot`` with new zero offsets, one per joint."""
    joints = tuple(
        dataclasses.replace(j, zero_offset_rad=o)
        for j, o in zip(robot.joints, offsets, strict=True)
    )
    return dataclasses.replace(robot, joints=joints)


def refusals(
    chain: ChainSettings, zeros: Sequence[JointZero], max_offset_deg: float = MAX_OFFSET_DEG
) -> list[str]:
    """Why these offsets must not be written (empty when they are fine)."""
    out = [
        f"joint {z.joint} (servo {z.servo_id}) is {math.degrees(z.angle_rad):+.1f} deg from "
        f"its servo's centre, beyond ±{max_offset_deg:g} deg: is the snake laid straight, the "
        "horn mounted on its mark?"
        for z in zeros
        if abs(math.degrees(z.angle_rad)) > max_offset_deg
    ]
    if out:
        return out
    robot = with_offsets(chain.robot, [z.new_offset_rad for z in zeros])
    values = {s.servo_id: {x.key: x.raw for x in s.settings} for s in chain.servos}
    errors, _ = check_settings(
        values,
        robot.servo_ids,
        TickConverter.for_robot(robot),
        watchdog=has_watchdog(chain),
        position_mode=chain.table.specs.position_mode,
        current_position_mode=current_position_mode(chain.table),
        shutdown_register=shutdown_name(chain.table),
    )
    return [f"{e}: widen the Position Limits in the settings" for e in errors]


def write_homing_offsets(link: Link, chain: ChainSettings, zeros: Sequence[JointZero]) -> None:
    """Write each servo's new Homing Offset (where ``zeros`` has one) inside the family's EEPROM
    lock, torque off, then check that it reads back and that the servo now reads the position
    it should (Present = Actual - Offset). VerifyError naming the servo otherwise."""
    bus = link.at(chain.baud)
    for zero in zeros:
        if zero.homing_offset is None or zero.actual_ticks is None:
            continue
        servo_id = zero.servo_id
        if bus.read(servo_id, "torque_enable"):
            bus.write(servo_id, "torque_enable", 0)  # an EEPROM item
        link.unlock(servo_id, chain.baud)
        bus.write(servo_id, "homing_offset", zero.homing_offset)
        back = bus.read(servo_id, "homing_offset")
        if back != zero.homing_offset:
            raise VerifyError(link.port, servo_id, "homing_offset", zero.homing_offset, back)
        link.relock(servo_id, chain.baud)
        present = bus.read(servo_id, "present_position")
        expected = zero.actual_ticks - zero.homing_offset
        if abs(present - expected) > MOVED_TICKS:
            raise SetupError(
                f"{link.port}: servo {servo_id} reads {present} ticks after its Homing Offset "
                f"{zero.homing_offset} was written, not {expected} (Present = Actual - Offset): "
                "did the joint move? Lay the snake straight and calibrate again"
            )


def write_offsets(robot: RobotConfig, zeros: Sequence[JointZero], path: Path | None = None) -> None:
    """Write the new offsets (rad) into robot file ``path`` (default the robot's own) in place,
    then reload it to check. ConfigError if the joints table cannot be edited, OutputError if
    the file cannot be written, SetupError (file restored) if the edit does not load back."""
    path = robot.source if path is None else path
    original = path.read_text(encoding="utf-8")
    try:
        text = set_in_joints(
            original, "zero_offset_rad", [format_float(z.new_offset_rad) for z in zeros]
        )
    except ValueError as exc:
        raise ConfigError(path, "joints", str(exc)) from None
    try:
        write_atomic(path, text)
    except OSError as exc:
        raise OutputError(
            path, f"cannot write the offsets ({exc.strerror or exc}); the file is unchanged"
        ) from exc
    try:
        loaded = load_robot(path)
        ok = all(
            math.isclose(j.zero_offset_rad, float(format_float(z.new_offset_rad)))
            for j, z in zip(loaded.joints, zeros, strict=True)
        )
    except ConfigError:
        ok = False
    if not ok:
        write_atomic(path, original)
        raise SetupError(
            f"{path}: the edited file did not load back with the new offsets; "
            "it was restored unchanged"
        )
