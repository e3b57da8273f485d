"""The robots of other servo families run every gait their axes allow over the emulator and in
hardware-in-the-loop, not only on the twin.

snake12-ax12a (12 x AX-12A on Protocol 1.0: one Read per servo a cycle, compliance loop),
snake8-2xl430 (four 2XL430 cases on Protocol 2.0) and snake12-sts3215 (12 x Feetech STS3215:
SYNC_READ, sign-magnitude registers, through scservo_sdk) drive the real ``ServoChainBackend`` and
runner through the unmodified vendor SDK against the in-process emulator, in virtual time: once
with the emulator's own motion model, once with every servo's shaft a joint of the twin
(``--physics``).
Every Goal Position a servo receives lies inside its joint's limits, and the servos move with it.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from snakebot.backends.chain import ServoChainBackend
from snakebot.backends.chain.ticks import TickConverter
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.emulation import EmulatedChain, make_chain_for_ids, registered
from snakebot.emulation.physics import make_twin_chain
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.emulation.port_feetech import EmulatedScsPortHandler
from snakebot.gaits import gait_names
from snakebot.session import resolve_gait

ROBOTS = ("snake12-ax12a", "snake8-2xl430", "snake12-sts3215")
# The vendor SDK's port handler that opens the emulator's dxlemu:// URL.
HANDLERS = {"dynamixel": EmulatedPortHandler, "feetech": EmulatedScsPortHandler}
CHANNEL_GAITS = ("miller_sidewinding", "undulation")
# rectilinear drives an axial channel no servo snake has: the twin test checks it is refused.
GAITS = [g for g in gait_names() if g != "rectilinear"]


def chain_for(name: str, physics: str) -> EmulatedChain:
    robot = load_robot(name)
    if physics == "hil":
        chain, _ = make_twin_chain(robot, robot.bus.baud)
    else:
        chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, robot.bus.baud)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)  # as `config apply` leaves them
    return chain


@pytest.mark.parametrize("physics", ["kinematic", "hil"])
@pytest.mark.parametrize("gait_name", GAITS)
@pytest.mark.parametrize("name", ROBOTS)
def test_every_gait_its_axes_allow_runs_over_the_emulator(
    name: str, gait_name: str, physics: str
) -> None:
    robot = load_robot(name)
    params: dict[str, object] | None = None
    if gait_name in CHANNEL_GAITS:
        params = {"channels": "yaw,pitch"}
    elif gait_name == "simple":  # holds a pose: all zeros by default, which would not move
        params = {"pose": [0.3, -0.3] * (robot.joint_count // 2)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a planar wave on yaw/pitch joints warns
        _, gait = resolve_gait(robot, gait_name, params=params)
    chain = chain_for(name, physics)
    goals: list[list[int]] = []
    present: list[list[int]] = []

    def record(cycle: object, t: float) -> None:
        goals.append([s.peek("goal_position") for s in chain.servos])
        present.append([s.peek("present_position") for s in chain.servos])

    with registered(chain) as url:
        backend = ServoChainBackend(
            robot,
            port=url,
            port_handler_factory=HANDLERS[chain.servos[0].vendor],
            clock=lambda: chain.now_s,
            sleep=chain.advance,
        )
        with backend:
            run_gait(
                backend,
                gait,
                SafetyLayer.for_robot(robot),
                RunPlan(duration_s=1.5),
                RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
                on_cycle=record,
            )
    converter = TickConverter.for_robot(robot)
    goal, now = np.array(goals), np.array(present)
    assert len(goals) >= 120, f"{gait_name}: {len(goals)} cycles"  # 1.5 s at 100 Hz + ramp-out
    assert np.all(goal >= converter.lower_ticks) and np.all(goal <= converter.upper_ticks), (
        f"{gait_name}: a goal outside the joint limits"
    )
    moved = np.abs(goal - goal[0]).max() / converter.ticks.ticks_per_rad
    followed = np.abs(now - now[0]).max() / converter.ticks.ticks_per_rad
    assert moved > 0.1, f"{gait_name}: the gait did not reach the servos ({moved:.3f} rad)"
    assert followed > 0.05, f"{gait_name}: the servos did not move ({followed:.3f} rad)"
