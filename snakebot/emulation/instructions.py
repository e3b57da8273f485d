"""Run one Protocol 2.0 instruction on the servos that hear it and say who answers with what.

The result is a list of reply slots in wire order (Sync/Bulk Read answer in parameter order,
broadcast ping in ID order); servos in the same slot answer at the same time and collide.
Status Return Level and the broadcast rules decide who answers (reference §1.5, §2.4).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from snakebot.emulation.protocol import (
    BROADCAST_ID,
    MAX_PACKET_BYTES,
    Instruction,
    Packet,
    StatusError,
    build_status,
    crc16,
    fast_reply_bytes,
    fast_status_header,
    fast_status_segment,
)
from snakebot.emulation.virtual_servo import VirtualServo

FACTORY_RESET_ALL = 0xFF


@dataclass(frozen=True)
class Slot:
    """Replies that start together; `segment` marks a later part of one Fast Read packet."""

    replies: tuple[tuple[VirtualServo, bytes], ...]
    segment: bool = False


def _u16(data: bytes, offset: int) -> int:
    return data[offset] | (data[offset + 1] << 8)


def _read_reply(servo: VirtualServo, address: int, length: int) -> tuple[int, bytes]:
    """(error byte, data) of a read; a failed read still carries `length` zeros for the SDK."""
    error, data = servo.read(address, length)
    if error:
        data = _zeros(length)
    return servo.status_error(error), data


def _zeros(length: int) -> bytes:
    """`length` zero bytes, or none when that many could not fit in a packet."""
    return bytes(length) if length <= MAX_PACKET_BYTES - 11 else b""


def by_id(servos: Sequence[VirtualServo]) -> dict[int, list[VirtualServo]]:
    """The servos by ID, in bus order (a group instruction finds each entry's servos in O(1))."""
    found: dict[int, list[VirtualServo]] = {}
    for servo in servos:
        found.setdefault(servo.servo_id, []).append(servo)
    return found


def _answers(servo: VirtualServo, instruction: int) -> bool:
    level = servo.status_return_level
    if instruction == Instruction.PING:
        return True
    reads = (
        Instruction.READ,
        Instruction.SYNC_READ,
        Instruction.FAST_SYNC_READ,
        Instruction.BULK_READ,
        Instruction.FAST_BULK_READ,
    )
    return level >= 1 if instruction in reads else level >= 2


def _unicast(packet: Packet, servo: VirtualServo) -> tuple[int, bytes]:
    """Execute a single-target instruction on `servo`; returns (error byte, params) of its reply."""
    inst, params = packet.instruction, packet.params
    if inst == Instruction.PING:
        return servo.status_error(), servo.ping_params()
    if inst == Instruction.READ:
        if len(params) != 4:
            return servo.status_error(StatusError.DATA_LENGTH), b""
        return _read_reply(servo, _u16(params, 0), _u16(params, 2))
    if inst in (Instruction.WRITE, Instruction.REG_WRITE):
        if len(params) < 3:
            return servo.status_error(StatusError.DATA_LENGTH), b""
        run = servo.write if inst == Instruction.WRITE else servo.reg_write
        error = run(_u16(params, 0), params[2:])
        return servo.status_error(error), b""
    if inst == Instruction.ACTION:
        return servo.status_error(servo.action()), b""
    if inst == Instruction.REBOOT:
        error = servo.status_error()
        servo.reboot()
        return error, b""
    if inst == Instruction.FACTORY_RESET:
        if len(params) != 1:
            return servo.status_error(StatusError.DATA_LENGTH), b""
        error = servo.status_error()
        code = servo.factory_reset(params[0])
        return servo.status_error(code) if code else error, b""
    if inst == Instruction.CLEAR:
        return servo.status_error(servo.clear(params)), b""
    return servo.status_error(StatusError.INSTRUCTION), b""


def _single(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    targets = [s for s in servos if s.servo_id == packet.servo_id]
    shadow = [s for s in servos if s.secondary_id == packet.servo_id and s not in targets]
    for servo in shadow:
        if packet.instruction not in (Instruction.PING, Instruction.READ):
            _unicast(packet, servo)
    replies = []
    for servo in targets:
        servo_id = servo.servo_id
        error, data = _unicast(packet, servo)
        if _answers(servo, packet.instruction):
            replies.append((servo, build_status(servo_id, error, data)))
    return [Slot(tuple(replies))] if replies else []


def _broadcast(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    inst = packet.instruction
    if inst == Instruction.PING:
        slots = []
        for servo_id in sorted({s.servo_id for s in servos}):
            same = [s for s in servos if s.servo_id == servo_id]
            slots.append(
                Slot(
                    tuple(
                        (s, build_status(servo_id, s.status_error(), s.ping_params())) for s in same
                    )
                )
            )
        return slots
    if inst == Instruction.FACTORY_RESET and packet.params[:1] == bytes([FACTORY_RESET_ALL]):
        return []  # Ignored since FW 42 (e-Manual protocol2 Factory Reset).
    if inst in (
        Instruction.WRITE,
        Instruction.REG_WRITE,
        Instruction.ACTION,
        Instruction.REBOOT,
        Instruction.FACTORY_RESET,
        Instruction.CLEAR,
    ):
        for servo in servos:
            _unicast(packet, servo)
    return []


def _sync_read(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    params = packet.params
    if len(params) < 5:
        return []
    address, length = _u16(params, 0), _u16(params, 2)
    fast = packet.instruction == Instruction.FAST_SYNC_READ
    requests = [(servo_id, address, length) for servo_id in params[4:]]
    return _reads(requests, servos, fast, packet.instruction)


def _bulk_read(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    params = packet.params
    if not params or len(params) % 5:
        return []
    requests = [
        (params[i], _u16(params, i + 1), _u16(params, i + 3)) for i in range(0, len(params), 5)
    ]
    fast = packet.instruction == Instruction.FAST_BULK_READ
    return _reads(requests, servos, fast, packet.instruction)


def _reads(
    requests: list[tuple[int, int, int]],
    servos: Sequence[VirtualServo],
    fast: bool,
    instruction: int,
) -> list[Slot]:
    """Slots of a (Fast) Sync/Bulk Read in parameter order; fast replies form one packet."""
    if fast and fast_reply_bytes(length for _, _, length in requests) > MAX_PACKET_BYTES:
        # The servos share one packet that no buffer holds (the SDK's is 1024 bytes, and its
        # 16-bit LEN may overflow): nobody answers, as ROBOTIS's reference slave
        # (Dynamixel2Arduino `Slave`) sends nothing when a reply would not fit its buffer.
        return []
    servos_by_id = by_id(servos)
    answers: list[list[tuple[VirtualServo, int, bytes]]] = []
    for servo_id, address, length in requests:
        row = []
        for servo in servos_by_id.get(servo_id, ()):
            if _answers(servo, instruction):
                error, data = _read_reply(servo, address, length)
                row.append((servo, error, data))
        answers.append(row)
    if not fast:
        return [
            Slot(tuple((s, build_status(s.servo_id, e, d)) for s, e, d in row))
            for row in answers
            if row
        ]
    if not any(answers):
        return []
    # A silent servo's part is what the others assume it sent: no error, `length` zeros.
    entries = [
        (servo_id, row[0][1], row[0][2]) if row else (servo_id, 0, _zeros(length))
        for (servo_id, _, length), row in zip(requests, answers, strict=True)
    ]
    # Each servo continues the CRC of what the others sent before it (one running CRC, so a
    # reply costs time linear in its length); servos sharing an ID each send their own part.
    header = fast_status_header(entries)
    crc = crc16(header)
    slots: list[Slot] = []
    for index, (entry, row) in enumerate(zip(entries, answers, strict=True)):
        replies = []
        for servo, error, data in row:
            segment = fast_status_segment(crc, servo.servo_id, error, data)
            replies.append((servo, header + segment if index == 0 else segment))
        if replies:
            slots.append(Slot(tuple(replies), segment=index > 0))
        crc = crc16(fast_status_segment(crc, *entry), crc)
    return slots


def _sync_write(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    params = packet.params
    if len(params) < 4:
        return []
    address, length = _u16(params, 0), _u16(params, 2)
    stride = 1 + length
    if length == 0 or (len(params) - 4) % stride:
        return []
    servos_by_id = by_id(servos)
    for offset in range(4, len(params), stride):
        for servo in servos_by_id.get(params[offset], ()):
            servo.write(address, params[offset + 1 : offset + stride])
    return []


def _bulk_write(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    params, offset = packet.params, 0
    servos_by_id = by_id(servos)
    while offset + 5 <= len(params):
        servo_id, address, length = (
            params[offset],
            _u16(params, offset + 1),
            _u16(params, offset + 3),
        )
        data = params[offset + 5 : offset + 5 + length]
        if len(data) != length:
            return []
        for servo in servos_by_id.get(servo_id, ()):
            servo.write(address, data)
        offset += 5 + length
    return []


_GROUP: dict[int, Callable[[Packet, Sequence[VirtualServo]], list[Slot]]] = {
    Instruction.SYNC_READ: _sync_read,
    Instruction.FAST_SYNC_READ: _sync_read,
    Instruction.BULK_READ: _bulk_read,
    Instruction.FAST_BULK_READ: _bulk_read,
    Instruction.SYNC_WRITE: _sync_write,
    Instruction.BULK_WRITE: _bulk_write,
}


def execute(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    """Run `packet` on the servos that hear it; return the reply slots in wire order."""
    if packet.is_status:
        return []
    for servo in servos:
        if packet.servo_id in (servo.servo_id, BROADCAST_ID, servo.secondary_id):
            servo.note_packet()
    group = _GROUP.get(packet.instruction)
    if group is not None:
        return group(packet, servos) if packet.servo_id == BROADCAST_ID else []
    if packet.servo_id == BROADCAST_ID:
        return _broadcast(packet, servos)
    return _single(packet, servos)
