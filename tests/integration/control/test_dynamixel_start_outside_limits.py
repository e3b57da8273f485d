"""A joint resting outside its joint limits at start is brought inside at the slew limit.

Real dynamixel_sdk over the in-process emulator (virtual time): snake12's joint 2 rests at
2.5 rad (limits ±1.5 rad; the servo's factory Min/Max Position Limit 0..4095 let it hold there).
Every Goal Position servo 3 receives, from torque on to the end, is recorded.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from snakebot.backends.chain import ServoChainBackend
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.emulation import make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.gaits import make_gait

RAD_PER_TICK = 2 * math.pi / 4096


def test_a_joint_resting_outside_its_limits_is_brought_in_never_stepped() -> None:
    base = load_robot("snake12")
    robot = dataclasses.replace(base, safety=dataclasses.replace(base.safety, ramp_s=0.5))
    chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud=robot.bus.baud)
    for each in chain.servos:
        each.poke("return_delay_time", 0)
    servo = chain.servo(3)
    servo.state = dataclasses.replace(servo.state, position_rad=2.5)
    servo.poke("goal_position", 2048)  # a stale goal it must not jump to either
    goals: list[int] = []
    with registered(chain) as url:
        backend = ServoChainBackend(
            robot,
            port=url,
            port_handler_factory=EmulatedPortHandler,
            clock=lambda: chain.now_s,
            sleep=chain.advance,
        )
        with backend:
            goals.append(servo.peek("goal_position"))  # Goal = Present at torque on
            run_gait(
                backend,
                make_gait("serpenoid", 12),
                SafetyLayer.for_robot(robot),
                RunPlan(duration_s=1.0),
                RunMetrics(12, robot.body_length_m, robot.total_mass_kg),
                on_cycle=lambda cycle, t: goals.append(servo.peek("goal_position")),
            )
    angles = (np.array(goals) - 2048) * RAD_PER_TICK
    assert abs(angles[0] - 2.5) < 2 * RAD_PER_TICK
    step_limit = robot.max_speed_rad_s * 0.01 + RAD_PER_TICK  # one 100 Hz cycle, one tick
    assert np.max(np.abs(np.diff(angles))) <= step_limit
    inside = int(np.argmax(angles <= 1.5))
    assert inside > 0 and np.all(np.diff(angles[: inside + 1]) <= 0)  # straight in, never out
    assert np.all(angles[inside:] <= 1.5 + 1e-9)  # and it stays inside
    assert np.all(angles <= 2.5 + RAD_PER_TICK)
