"""What protects a Feetech servo when the host dies is checked at connect (docs/hardware.md).

No Feetech servo has a bus watchdog, so its Unload Condition (19) is what cuts torque on a joint
held against an obstacle after the host died: connect refuses a servo whose Unload Condition
lacks the overheating or the overload bit (the bits of Dynamixel's Alarm Shutdown), naming the
servo and the register by the model's own name.
"""

from __future__ import annotations

import pytest

from snakebot.backends.chain import ServoChainBackend
from snakebot.backends.chain.faults import ServoSettingsError
from snakebot.config import load_robot
from snakebot.emulation import make_chain_for_ids, registered
from snakebot.emulation.port_feetech import EmulatedScsPortHandler


@pytest.mark.parametrize(("unload", "refused"), [(8, True), (0x04 | 0x08, True), (44, False)])
def test_connect_refuses_an_unload_condition_without_heat_and_overload(
    unload: int, refused: bool
) -> None:
    robot = load_robot("snake12-sts3215")
    chain = make_chain_for_ids("STS3215", robot.servo_ids, robot.bus.baud)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)  # as `config apply` leaves them
    chain.servo(6).poke("shutdown", unload)
    with registered(chain) as url:
        backend = ServoChainBackend(
            robot,
            port=url,
            port_handler_factory=EmulatedScsPortHandler,
            clock=lambda: chain.now_s,
            sleep=chain.advance,
        )
        if not refused:
            with backend:
                assert chain.servo(6).torque_enabled
            return
        with pytest.raises(ServoSettingsError) as caught:
            backend.connect()
    assert f"servo 6: Unload Condition is {unload}, needs bits 2 and 5" in str(caught.value)
    assert "with no Bus Watchdog" in str(caught.value)
    assert not any(s.torque_enabled for s in chain.servos)
