"""The emulated Feetech servo reports each fault in its own status bit, as the stock scservo_sdk
decodes it (ERRBIT_VOLTAGE 1, ERRBIT_ANGLE 2, ERRBIT_OVERHEAT 4, ERRBIT_OVERELE 8,
ERRBIT_OVERLOAD 32; servo-families.md §1.3), not in Dynamixel's Hardware Error bits."""

from __future__ import annotations

import pytest
import scservo_sdk as scs

from snakebot.emulation import EmulatedChain, Fault, make_chain_for_ids, registered
from snakebot.emulation.port_feetech import EmulatedScsPortHandler

SDK_BIT = {
    Fault.INPUT_VOLTAGE: scs.ERRBIT_VOLTAGE,
    Fault.ENCODER: scs.ERRBIT_ANGLE,
    Fault.OVERHEATING: scs.ERRBIT_OVERHEAT,
    Fault.OVERCURRENT: scs.ERRBIT_OVERELE,
    Fault.OVERLOAD: scs.ERRBIT_OVERLOAD,
}


def status_byte(chain: EmulatedChain, servo_id: int) -> tuple[int, str]:
    """A PING through the stock SDK: the reply's error byte and the SDK's text for it."""
    with registered(chain) as url:
        port = EmulatedScsPortHandler(url)
        assert port.setBaudRate(1_000_000)
        packet = scs.sms_sts(port)
        _, result, error = packet.ping(servo_id)
        port.closePort()
    assert result == scs.COMM_SUCCESS
    return error, packet.getRxPacketError(error)


@pytest.mark.parametrize("fault", list(SDK_BIT), ids=lambda f: f.name.lower())
def test_each_fault_sets_the_bit_the_sdk_names_for_it(fault: Fault) -> None:
    chain = make_chain_for_ids("STS3215", range(1, 4), 1_000_000)
    chain.latch_fault(2, fault)
    error, text = status_byte(chain, 2)
    assert error == SDK_BIT[fault]
    assert text  # the SDK has a message for every one of them
    assert status_byte(chain, 1)[0] == 0  # the others are fine


def test_a_current_above_protection_current_sets_the_overcurrent_bit() -> None:
    """Protection Current (28, 6.5 mA) exceeded for the Overcurrent Protection Time (38,
    10 ms) latches bit 3; a Dynamixel status byte has no such fault."""
    chain = make_chain_for_ids("STS3215", range(1, 4), 1_000_000)
    servo = chain.servo(2)
    servo.poke("protection_current", 1)  # 6.5 mA: any moving motor draws more
    servo.poke("overcurrent_protection_time", 1)
    servo.poke("shutdown", 0)  # report it, keep the torque on
    servo.poke("torque_enable", 1)
    servo.poke("goal_position", 3000)
    for _ in range(50):
        chain.advance(0.002)
    error, text = status_byte(chain, 2)
    assert error & scs.ERRBIT_OVERELE, text
    assert not error & scs.ERRBIT_ANGLE
    assert status_byte(chain, 1)[0] == 0
