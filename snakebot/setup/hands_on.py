"""Hands-on servo tools: torque off (limp) or on (hold where it stands), and jogging one joint.

A jog lets the servo's own profile generator ramp the move (e-Manual X-series: Profile Velocity
112, Profile Acceleration 108, velocity-based while Drive Mode bit 2 is clear; an AX or an MX on
Protocol 1.0 has only Moving Speed 32, no acceleration limit): the registers are set for the move
and put back afterwards, so ``config diff`` stays clean. Angles are joint angles
of the robot file (direction and zero offset applied), the ones ``snakebot run`` commands. Time is
the port's own clock (the SDK's; the emulated bus clock for ``dxlemu://``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from snakebot.backends.chain.faults import ServoStatusError, decode_hardware_error
from snakebot.errors import BusError
from snakebot.servo.ticks import rad_to_ticks, ticks_to_rad
from snakebot.setup.errors import SetupError
from snakebot.setup.link import Link
from snakebot.setup.settings import ChainSettings

JOG_SPEED_RAD_S = math.radians(30.0)
"""Default jog speed: slow enough to watch and to catch the joint."""
JOG_RAMP_S = 0.25
"""Time the servo takes to reach the jog speed (Profile Acceleration)."""
ARRIVED_TICKS = 6
"""A jog has arrived within this many ticks of its goal (0.5 deg on a 4096-tick servo)."""
SETTLE_S = 0.1
"""A jog within ARRIVED_TICKS whose position has not changed for this long has arrived."""
_STATE = (
    "torque_enable",
    "hardware_error_status",
    "present_position",
    "min_position_limit",
    "max_position_limit",
)
_PREREQUISITES = ("operating_mode", "drive_mode", "homing_offset")


@dataclass(frozen=True)
class ServoState:
    """What one servo holds now: torque, latched errors, position and Position Limits (ticks)."""

    servo_id: int
    torque_on: bool
    errors: tuple[str, ...]
    present_ticks: int
    limits: tuple[int, int]


@dataclass(frozen=True)
class JogResult:
    """One jog: joint angles (rad) at the start, asked for and reached, and the bus time taken."""

    joint: int
    servo_id: int
    start_rad: float
    target_rad: float
    end_rad: float
    seconds: float


def read_states(link: Link, ids: Sequence[int], baud: int) -> list[ServoState]:
    """Torque, errors, position and limits of ``ids``; BusError naming the IDs that are silent."""
    bus = link.at(baud)
    answered = bus.ping_all(ids)
    missing = [i for i in ids if i not in answered]
    if missing:
        raise BusError(
            link.port,
            missing,
            f"no answer at {baud} baud; `snakebot scan --port "
            f"{link.port} --all-bauds` shows where the servos are",
        )
    states = []
    keys = [k for k in _STATE if k in bus.table]  # an AX has no Hardware Error Status
    for servo_id in ids:
        v = bus.read_block(servo_id, keys)
        states.append(
            ServoState(
                servo_id,
                bool(v["torque_enable"]),
                decode_hardware_error(v.get("hardware_error_status", 0)),
                v["present_position"],
                (v["min_position_limit"], v["max_position_limit"]),
            )
        )
    return states


def torque_on_refusals(states: Sequence[ServoState]) -> list[str]:
    """Why torque must not come on (empty when it may): a latched error, or a servo outside its
    Position Limits (it would jump to the limit instead of holding where it stands)."""
    out = []
    for s in states:
        if s.errors:
            out.append(
                f"servo {s.servo_id} has a latched hardware error ({', '.join(s.errors)}) "
                "and keeps torque off: remove the cause, then `snakebot servo reboot`"
            )
        elif not s.limits[0] <= s.present_ticks <= s.limits[1]:
            out.append(
                f"servo {s.servo_id} stands at tick {s.present_ticks}, outside its Min/Max "
                f"Position Limit {s.limits[0]}..{s.limits[1]}: it would jump to the limit; "
                "move the joint inside by hand"
            )
    return out


def set_torque(link: Link, ids: Sequence[int], baud: int, *, on: bool) -> None:
    """Torque off (the joints go limp) or on, holding each joint where it stands now (Goal
    Position := Present Position first, so nothing jumps); each read back."""
    bus = link.at(baud)
    for servo_id in ids:
        if on:
            bus.write(servo_id, "goal_position", bus.read(servo_id, "present_position"))
        bus.write(servo_id, "torque_enable", int(on))
        if bool(bus.read(servo_id, "torque_enable")) != on:
            raise SetupError(
                f"{link.port}: servo {servo_id} did not turn torque "
                f"{'on' if on else 'off'}; `snakebot servo info` shows why"
            )


def check_jog(chain: ChainSettings, joint: int, target_rad: float, speed_rad_s: float) -> None:
    """SetupError unless ``joint`` exists, ``target_rad`` lies within its limits and
    ``speed_rad_s`` within the robot's joint speed limit (the safety layer's slew limit)."""
    robot = chain.robot
    if not 0 <= joint < len(robot.joints):
        raise SetupError(f"{robot.name} has joints 0..{len(robot.joints) - 1}, not {joint}")
    j = robot.joints[joint]
    if not j.lower_rad <= target_rad <= j.upper_rad:
        raise SetupError(
            f"joint {joint} (servo {j.servo_id}): {math.degrees(target_rad):+.1f} deg is outside "
            f"its limits {math.degrees(j.lower_rad):+.1f}..{math.degrees(j.upper_rad):+.1f} deg "
            f"({j.lower_rad:g}..{j.upper_rad:g} rad, lower_rad/upper_rad in {robot.source})"
        )
    limit = robot.max_speed_rad_s
    if not 0.0 < speed_rad_s <= limit:
        raise SetupError(
            f"a jog speed of {math.degrees(speed_rad_s):.1f} deg/s is beyond "
            f"{robot.name}'s joint speed limit {math.degrees(limit):.1f} deg/s"
        )


def jog_limits(link: Link, speed_rad_s: float) -> dict[str, int]:
    """The registers (in write order) that make the servo ramp a jog at ``speed_rad_s`` itself:
    Profile Acceleration and Velocity (X, MX 2.0), or Moving Speed (AX, MX on Protocol 1.0, where
    0 means no limit: at least 1). SetupError for a model with neither."""
    table = link.bus.table
    if "profile_velocity" in table and "profile_acceleration" in table:
        return {
            "profile_acceleration": max(
                1, math.ceil(speed_rad_s / JOG_RAMP_S / table["profile_acceleration"].scale)
            ),
            "profile_velocity": max(1, math.floor(speed_rad_s / table["profile_velocity"].scale)),
        }
    if "moving_speed" in table:
        return {"moving_speed": max(1, math.floor(speed_rad_s / table["moving_speed"].scale))}
    raise SetupError(
        f"{link.port}: a {table.model} has no Profile Velocity or Moving Speed "
        "register to limit a jog's speed with"
    )


def jog(
    link: Link,
    chain: ChainSettings,
    joint: int,
    target_rad: float,
    *,
    speed_rad_s: float = JOG_SPEED_RAD_S,
) -> JogResult:
    """Move one joint from where it stands to ``target_rad`` at ``speed_rad_s``; it then holds
    there (torque on). SetupError (nothing moved) for a bad target, speed or servo state, or
    (holding where it got to) when it does not arrive."""
    check_jog(chain, joint, target_rad, speed_rad_s)
    robot, j = chain.robot, chain.robot.joints[joint]
    tpr = robot.servo.physics.ticks
    bus = link.at(chain.baud)
    (state,) = read_states(link, [j.servo_id], chain.baud)
    prerequisites = [k for k in _PREREQUISITES if k in bus.table]
    values = bus.read_block(j.servo_id, prerequisites) if prerequisites else {}
    wrong = [
        f"{k} is {values[k]}"
        for k in prerequisites
        if values[k] != chain.for_id(j.servo_id).get(k).raw
    ]
    if wrong:
        raise SetupError(
            f"{link.port}: servo {j.servo_id}: jogging needs the configured settings "
            f"({'; '.join(wrong)}): run `snakebot config apply --robot {robot.name}`"
        )
    problems = torque_on_refusals([state])
    goal = rad_to_ticks(
        target_rad, ticks=tpr, zero_offset_rad=j.zero_offset_rad, direction=j.direction
    )
    if not state.limits[0] <= goal <= state.limits[1]:
        problems.append(
            f"servo {j.servo_id}: tick {goal} is outside its Min/Max Position Limit "
            f"{state.limits[0]}..{state.limits[1]}"
        )
    if problems:
        raise SetupError(f"{link.port}: jog refused, nothing moved: {'; '.join(problems)}")

    def angle(ticks: int) -> float:
        return ticks_to_rad(
            ticks, ticks=tpr, zero_offset_rad=j.zero_offset_rad, direction=j.direction
        )

    table = bus.table
    limits = jog_limits(link, speed_rad_s)
    saved = bus.read_block(j.servo_id, tuple(limits))
    speed_key = next(iter(limits.keys() - {"profile_acceleration"}))
    speed = limits[speed_key] * table[speed_key].scale  # rad/s, as the register rounds it
    start_s = link.clock_s()
    present = state.present_ticks
    try:
        if not state.torque_on:
            set_torque(link, [j.servo_id], chain.baud, on=True)
        for key, value in limits.items():
            bus.write(j.servo_id, key, value)
        bus.write(j.servo_id, "goal_position", goal)
        travel_s = abs(goal - present) / (speed * tpr.ticks_per_rad)
        deadline = start_s + travel_s + 2 * JOG_RAMP_S + 2.0
        changed_s = start_s
        while abs(present - goal) > 1 and link.clock_s() < deadline:
            try:
                now = bus.read(j.servo_id, "present_position")
            except ServoStatusError:
                raise
            except BusError:
                continue  # a reply lost while watching: the servo moves on by its own profile
            if now != present:
                present, changed_s = now, link.clock_s()
            elif abs(present - goal) <= ARRIVED_TICKS and link.clock_s() - changed_s > SETTLE_S:
                break  # settled a few ticks short (a load against the P gain): arrived
    finally:
        held = bus.read(j.servo_id, "present_position")
        if abs(held - goal) > ARRIVED_TICKS:
            # Stop where it stands before the profiles go back (without them it would race on).
            bus.write(j.servo_id, "goal_position", held)
        for key in reversed(limits):
            bus.write(j.servo_id, key, saved[key])
    result = JogResult(
        joint,
        j.servo_id,
        angle(state.present_ticks),
        target_rad,
        angle(held),
        link.clock_s() - start_s,
    )
    if abs(held - goal) > ARRIVED_TICKS:
        raise SetupError(
            f"{link.port}: joint {joint} (servo {j.servo_id}) stopped at "
            f"{math.degrees(result.end_rad):+.1f} deg, short of {math.degrees(target_rad):+.1f} "
            "deg, and holds there: something blocks it, or the load is beyond the servo"
        )
    return result
