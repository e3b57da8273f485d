"""Zero offsets from a straight snake, written into the robot file (``joints[].zero_offset_rad``).

The one calibration convention (snakebot.servo.ticks, the Dynamixel backend's): the
offset lives in the robot config; the servo's Homing Offset stays 0 and its Drive Mode reverse bit
clear (the settings say so and ``config diff`` checks it). An AX has neither register: its offset
can only live in the robot file. With every joint straight (0 rad), a
servo reading ``ticks`` gets ``zero_offset_rad = direction * (ticks - centre) * 2 pi /
ticks`` (centre 2048 of 4096 on the X series, 512 of 1024 on an AX).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from snakebot.backends.dynamixel.checks import check_settings
from snakebot.backends.dynamixel.ticks import TickConverter
from snakebot.config import load_robot
from snakebot.config.schema import RobotConfig
from snakebot.errors import ConfigError, OutputError
from snakebot.servo.ticks import TickModel, ticks_to_rad
from snakebot.setup.errors import SetupError
from snakebot.setup.link import Link
from snakebot.setup.settings import ChainSettings, has_watchdog
from snakebot.setup.toml_edit import format_float, set_in_joints, write_atomic

MAX_OFFSET_DEG = 20.0
_PREREQUISITES = ("operating_mode", "drive_mode", "homing_offset")


@dataclass(frozen=True)
class JointZero:
    """One joint's measurement: the servo's present ticks and the old and new zero offsets."""

    joint: int
    servo_id: int
    present_ticks: int
    old_offset_rad: float
    new_offset_rad: float


def zero_offset_rad(ticks: int, direction: int, model: TickModel) -> float:
    """The zero offset that makes a servo reading ``ticks`` report 0 rad: the angle the tick
    means with no offset (snakebot.servo.ticks)."""
    return ticks_to_rad(ticks, ticks=model, direction=direction)


def measure(link: Link, chain: ChainSettings) -> list[JointZero]:
    """Read every servo's position (at the robot's baud) and compute the zero offsets."""
    robot = chain.robot
    bus = link.at(chain.baud)
    missing = [i for i in robot.servo_ids if i not in bus.ping_all(robot.servo_ids)]
    if missing:
        raise SetupError(
            f"{link.port}: servo(s) {', '.join(map(str, missing))} do not answer at {chain.baud} "
            f"baud; run `snakebot config diff --robot {robot.name} --port {link.port}` first"
        )
    wrong = []
    prerequisites = [k for k in _PREREQUISITES if k in bus.table]  # an AX has none of them
    for servo in chain.servos:
        values = bus.read_block(servo.servo_id, prerequisites) if prerequisites else {}
        for key in prerequisites:
            if values[key] != servo.get(key).raw:
                wrong.append(f"servo {servo.servo_id} {key} is {values[key]}")
    if wrong:
        raise SetupError(
            f"{link.port}: calibration needs the configured settings first ({'; '.join(wrong)}): "
            f"run `snakebot config apply --robot {robot.name} --port {link.port}`"
        )
    if link.family.capabilities(bus.table).sync_read:
        ticks = bus.sync_read("present_position", robot.servo_ids)
    else:  # Protocol 1.0: no Sync Read; one Read per servo is quick enough once
        ticks = {i: bus.read_block(i, ("present_position",)) for i in robot.servo_ids}
    tpr = robot.servo.physics.ticks
    return [
        JointZero(
            index,
            joint.servo_id,
            ticks[joint.servo_id]["present_position"],
            joint.zero_offset_rad,
            zero_offset_rad(ticks[joint.servo_id]["present_position"], joint.direction, tpr),
        )
        for index, joint in enumerate(robot.joints)
    ]


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
        f"joint {z.joint} (servo {z.servo_id}) is {math.degrees(z.new_offset_rad):+.1f} deg from "
        f"its servo's centre, beyond ±{max_offset_deg:g} deg: is the snake laid straight, the "
        "horn mounted on its mark?"
        for z in zeros
        if abs(math.degrees(z.new_offset_rad)) > max_offset_deg
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
    )
    return [f"{e}: widen the Position Limits in the settings" for e in errors]


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
