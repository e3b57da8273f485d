"""The drive display names a Protocol 1.0 servo's alarm as its status byte says it."""

from __future__ import annotations

import dataclasses

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.config import load_robot
from snakebot.drive.observers import backend_readings
from snakebot.emulation import make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler


def test_an_ax_overload_shows_by_name_before_the_slow_check_stops_the_run() -> None:
    base = load_robot("snake12-ax12a")
    robot = dataclasses.replace(base, safety=dataclasses.replace(base.safety, ramp_s=0.1))
    chain = make_chain_for_ids("AX-12A", robot.servo_ids, baud=robot.bus.baud)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    with registered(chain) as url:
        backend = ServoChainBackend(
            robot,
            port=url,
            port_handler_factory=EmulatedPortHandler,
            clock=lambda: chain.now_s,
            sleep=chain.advance,
        )
        with backend:
            _, alerts = backend_readings(backend)
            assert alerts() == ()
            chain.servo(5).latch_error(0x20)
            backend.read_state()  # one Read per servo: every status byte, every cycle
            assert "overload: servo 5" in alerts()
            chain.servo(5).clear_alarms()
            backend.read_state()
            assert alerts() == ()
