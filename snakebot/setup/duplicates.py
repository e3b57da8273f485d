"""Tell one servo from two sharing an ID: colliding replies come back corrupt or contradictory.

Two servos with one ID answer the same instruction at nearly the same time; a UART receiving both
sees garbage (a CRC error) unless the replies are bit-for-bit equal. Pings of identical models can
be equal, so Present Position (which differs between shafts) is read as well, and the model number
in the ping is compared with the Model Number register (mixed models sharing an ID).
"""

from __future__ import annotations

from snakebot.backends.dynamixel import sdk
from snakebot.setup.link import Link

CORRUPT = (sdk.COMM_RX_CORRUPT, sdk.COMM_RX_FAIL)


def collision_reason(link: Link, servo_id: int, baud: int) -> str | None:
    """Why the replies of ``servo_id`` at ``baud`` look like several servos; None if like one."""
    probe = link.probe(servo_id, baud, tries=2)
    if probe.collides:
        return probe.clash()
    models = sorted(set(probe.models))
    if not models:
        return None
    table = link.bus.table
    position = table["present_position"]
    for _ in range(2):
        _data, result = link.raw_read(servo_id, position.address, position.size)
        if result in CORRUPT:
            return "replies to a read of Present Position were corrupt"
    data, result = link.raw_read(servo_id, table["model_number"].address, 2)
    if result in CORRUPT:
        return "replies to a read of Model Number were corrupt"
    if result == sdk.COMM_SUCCESS and len(data) == 2:
        number = data[0] | data[1] << 8
        if number != models[0]:
            return f"ping says model {models[0]}, the Model Number register says {number}"
    return None
