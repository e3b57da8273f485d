"""Run one Protocol 1.0 instruction on the servos that hear it and say who answers with what.

The instruction set of the e-Manual's protocol1.md: PING, READ, WRITE, REG_WRITE, ACTION,
FACTORY_RESET, SYNC_WRITE and BULK_READ. Anything else (Sync Read, Reboot, ...) is answered with
the Instruction bit. A broadcast gets no status packet, not even a ping. A frame whose checksum
failed is answered, by the servo it names, with the Checksum bit. In a Bulk Read each servo
transmits after the status of the ID before it in the request, so the first servo that stays
silent (absent, or a model without Bulk Read such as the AX-12A) silences the rest.

The servo's firmware reports Protocol 2.0 error numbers (`protocol.StatusError`); this module
turns them into Protocol 1.0 bits. Writes that the firmware refuses for access, length or range
reasons all read as the Range bit: P1 has no Data Length or Access error, and a write of one
byte to a two-byte register is taken to be a Range error (an assumption: no ROBOTIS text says;
servo-families.md §4). A Goal Position outside the angle limits reads as the Angle Limit bit.
"""

from __future__ import annotations

from collections.abc import Sequence

from snakebot.emulation.instructions import Slot, by_id
from snakebot.emulation.protocol import StatusError
from snakebot.emulation.protocol1 import (
    BROADCAST_ID,
    MAX_PACKET_BYTES,
    ErrorBit,
    Instruction,
    Packet,
    build_status,
)
from snakebot.emulation.virtual_servo import VirtualServo

_READS = (Instruction.PING, Instruction.READ, Instruction.BULK_READ)
# Protocol 2.0 error numbers the firmware returns, as Protocol 1.0 bits.
_P1_BITS: dict[int, ErrorBit] = {
    StatusError.NONE: ErrorBit.NONE,
    StatusError.INSTRUCTION: ErrorBit.INSTRUCTION,
    StatusError.CRC: ErrorBit.CHECKSUM,
}


def error_byte(servo: VirtualServo, error: int = 0, *, goal_position: bool = False) -> int:
    """A status packet's error byte: the alarm bits the servo has now, plus what `error` (a
    Protocol 2.0 error number from the firmware) means in Protocol 1.0."""
    if error == StatusError.DATA_LIMIT and goal_position:
        bits = ErrorBit.ANGLE_LIMIT
    else:
        bits = _P1_BITS.get(error, ErrorBit.RANGE) if error else ErrorBit.NONE
    return int(bits) | servo.alarm_bits()


def _answers(servo: VirtualServo, instruction: int) -> bool:
    """Status Return Level: 0 ping only, 1 ping and reads, 2 every instruction."""
    if instruction == Instruction.PING:
        return True
    level = servo.status_return_level
    return level >= 1 if instruction in _READS else level >= 2


def _read(servo: VirtualServo, params: bytes) -> tuple[int, bytes]:
    if len(params) != 2:
        return error_byte(servo, StatusError.DATA_LENGTH), b""
    address, length = params
    error, data = servo.read(address, length)
    if error or len(data) != length or length > MAX_PACKET_BYTES - 6:
        # A refused read still carries `length` zeros where they fit, as the Protocol 2.0 side
        # does, so the SDK reads the error rather than a short packet.
        fits = 0 < length <= MAX_PACKET_BYTES - 6
        return error_byte(servo, error or StatusError.DATA_RANGE), bytes(length if fits else 0)
    return error_byte(servo), data


def _covers_goal(servo: VirtualServo, address: int, size: int) -> bool:
    if not servo.memory.has("goal_position"):
        return False
    goal = servo.memory.by_key["goal_position"]
    return address < goal.address + goal.size and goal.address < address + size


def _write(servo: VirtualServo, params: bytes, *, registered: bool) -> int:
    if len(params) < 2:
        return error_byte(servo, StatusError.DATA_LENGTH)
    address, data = params[0], params[1:]
    error = servo.reg_write(address, data) if registered else servo.write(address, data)
    return error_byte(servo, error, goal_position=_covers_goal(servo, address, len(data)))


def _factory_reset(servo: VirtualServo) -> None:
    """Everything back to factory defaults, ID and baud rate included (Protocol 1.0 has no
    options). An X servo keeps Protocol Type 1: it answers on in the protocol it was reset in
    (an assumption, no ROBOTIS text says; ROBOTIS's Protocol 1.0 factory-reset example reads the
    servo back in 1.0 after the reset)."""
    servo.factory_reset(0xFF)
    if servo.memory.has("protocol_type"):
        servo.memory.set("protocol_type", 1)


def _unicast(packet: Packet, servo: VirtualServo) -> tuple[int, bytes]:
    """Execute a single-target instruction on `servo`; returns (error byte, params) of its reply."""
    inst, params = packet.instruction, packet.params
    if inst == Instruction.PING:
        return error_byte(servo), b""
    if inst == Instruction.READ:
        return _read(servo, params)
    if inst in (Instruction.WRITE, Instruction.REG_WRITE):
        return _write(servo, params, registered=inst == Instruction.REG_WRITE), b""
    if inst == Instruction.ACTION:
        return error_byte(servo, servo.action()), b""
    if inst == Instruction.FACTORY_RESET:
        error = error_byte(servo)  # the reply leaves before the reset (old ID and baud)
        _factory_reset(servo)
        return error, b""
    return error_byte(servo, StatusError.INSTRUCTION), b""


def _single(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    replies = []
    for servo in servos:
        if servo.servo_id != packet.servo_id:
            continue
        if not packet.intact:
            error, data = int(ErrorBit.CHECKSUM) | servo.alarm_bits(), b""
        else:
            error, data = _unicast(packet, servo)
        if _answers(servo, packet.instruction):
            replies.append((servo, build_status(packet.servo_id, error, data)))
    return [Slot(tuple(replies))] if replies else []


def _sync_write(packet: Packet, servos: Sequence[VirtualServo]) -> None:
    params = packet.params
    if len(params) < 2:
        return
    address, length = params[0], params[1]
    stride = 1 + length
    if length == 0 or (len(params) - 2) % stride:
        return
    servos_by_id = by_id(servos)
    for offset in range(2, len(params), stride):
        for servo in servos_by_id.get(params[offset], ()):
            servo.write(address, params[offset + 1 : offset + stride])


def _bulk_read(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    params = packet.params
    if len(params) < 4 or (len(params) - 1) % 3:
        return []
    slots: list[Slot] = []
    servos_by_id = by_id(servos)
    for offset in range(1, len(params), 3):
        length, servo_id, address = params[offset : offset + 3]
        replies = []
        for servo in servos_by_id.get(servo_id, ()):
            if servo.table.specs.bulk_read and _answers(servo, Instruction.BULK_READ):
                error, data = _read(servo, bytes([address, length]))
                replies.append((servo, build_status(servo_id, error, data)))
        if not replies:
            break  # the next servo waits for a status that never comes
        slots.append(Slot(tuple(replies)))
    return slots


def execute(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    """Run `packet` on the Protocol 1.0 servos that hear it; return the reply slots in wire
    order."""
    for servo in servos:
        if packet.servo_id in (servo.servo_id, BROADCAST_ID):
            servo.note_packet()
    if packet.servo_id != BROADCAST_ID:
        return _single(packet, servos)
    if not packet.intact:
        return []
    inst = packet.instruction
    if inst == Instruction.SYNC_WRITE:
        _sync_write(packet, servos)
    elif inst == Instruction.BULK_READ:
        return _bulk_read(packet, servos)
    elif inst in (
        Instruction.WRITE,
        Instruction.REG_WRITE,
        Instruction.ACTION,
        Instruction.FACTORY_RESET,
    ):
        for servo in servos:
            _unicast(packet, servo)
    return []
