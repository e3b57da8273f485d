"""Run one Feetech FT-SCS instruction on the servos that hear it and say who answers with what.

The instruction set of Feetech's wiki (protocol/ft-scs.md §4): PING, READ, WRITE, REG_WRITE,
ACTION, 0x06 parameter recovery (all but the ID), 0x08 restart (no reply), 0x09 parameter
backup, 0x0A status reset (the turn count), 0x0B position calibration, 0x82 SYNC_READ and
0x83 SYNC_WRITE. The status byte carries only the servo's condition (voltage, angle sensor,
overheat, overcurrent, overload): a refused write, an unknown instruction or a wrong length has
no bit, so a refused write is acknowledged and changes nothing, and an unknown instruction or a
frame whose checksum failed gets no reply (unverified on hardware; servo-families.md §1.3).

Response status level (8): 0 answers READ and PING only, 1 every instruction. A broadcast is
answered only by PING, and then by every servo at once ("the broadcast PING cannot be used when
multiple servos are connected"). In a SYNC_READ each servo answers in the order of the IDs in
the request, after the one before it; an absent ID is skipped (the SDK waits for the bytes of
all and finds each servo's status in them).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from snakebot.emulation import firmware, firmware_feetech
from snakebot.emulation.instructions import Slot, by_id
from snakebot.emulation.protocol_feetech import (
    BROADCAST_ID,
    MAX_PACKET_BYTES,
    Instruction,
    Packet,
    build_status,
)
from snakebot.emulation.virtual_servo import VirtualServo

_READS = (Instruction.PING, Instruction.READ, Instruction.SYNC_READ)
_MAX_READ = MAX_PACKET_BYTES - 6
"""The most data bytes one status packet carries."""
_BROADCAST_RUNS = (
    Instruction.WRITE,
    Instruction.REG_WRITE,
    Instruction.ACTION,
    Instruction.RECOVERY,
    Instruction.RESTART,
    Instruction.BACKUP,
    Instruction.RESET,
    Instruction.OFSCAL,
)


def error_byte(servo: VirtualServo) -> int:
    """The status byte: the servo's condition bits (Servo status (65) on an STS)."""
    return int(servo.hardware_error) & 0x7F


def _answers(servo: VirtualServo, instruction: int) -> bool:
    return instruction in _READS or servo.status_return_level >= 1


def read_data(servo: VirtualServo, address: int, length: int) -> bytes | None:
    """The bytes a READ of `length` at `address` returns (zeros past the table's end), or None
    when no reply could carry them."""
    if not 0 < length <= _MAX_READ:
        return None
    firmware_feetech.refresh_present(servo)
    data = bytes(servo.memory.data[address : address + length])
    return data + bytes(length - len(data))


def _write(servo: VirtualServo, params: bytes, *, registered: bool) -> None:
    if len(params) >= 2:
        address, data = params[0], params[1:]
        if registered:
            servo.reg_write(address, data)
        else:
            servo.write(address, data)


def _recovery(servo: VirtualServo) -> None:
    """Every parameter back to its factory value (or the last backup) except the ID; saved
    when Lock reads 0, as any EEPROM write."""
    unlocked = servo.memory.has("lock") and servo.memory.get("lock") == 0
    servo_id = servo.servo_id
    servo.recover_parameters()
    servo.memory.set("id", servo_id)
    if unlocked:
        servo.save_eeprom()
    servo.reboot()


def _ofscal(servo: VirtualServo, params: bytes) -> None:
    present = int.from_bytes(params, servo.memory.order) if len(params) == 2 else None
    firmware_feetech.calibrate_middle(servo, present)


def _unicast(packet: Packet, servo: VirtualServo) -> bytes | None:
    """Execute a single-target instruction on `servo`; its reply's data, or None for silence."""
    inst, params = packet.instruction, packet.params
    if inst == Instruction.PING:
        return b""
    if inst == Instruction.READ:
        return read_data(servo, params[0], params[1]) if len(params) == 2 else None
    if inst in (Instruction.WRITE, Instruction.REG_WRITE):
        _write(servo, params, registered=inst == Instruction.REG_WRITE)
    elif inst == Instruction.ACTION:
        servo.action()
    elif inst == Instruction.RECOVERY:
        _recovery(servo)
    elif inst == Instruction.BACKUP:
        servo.backup_parameters()
    elif inst == Instruction.RESET:
        servo.state = replace(
            servo.state, position_rad=firmware.wrap_turn(servo.state.position_rad)
        )
    elif inst == Instruction.OFSCAL:
        _ofscal(servo, params)
    else:
        return None
    return b""


def _single(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    replies = []
    for servo in servos:
        if servo.servo_id != packet.servo_id or not packet.intact:
            continue
        if packet.instruction == Instruction.RESTART:
            servo.power_cycle()  # no status packet
            continue
        data = _unicast(packet, servo)
        if data is not None and _answers(servo, packet.instruction):
            replies.append((servo, build_status(packet.servo_id, error_byte(servo), data)))
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


def _sync_read(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    params = packet.params
    if len(params) < 3:
        return []
    address, length = params[0], params[1]
    slots: list[Slot] = []
    servos_by_id = by_id(servos)
    for servo_id in params[2:]:
        replies = []
        for servo in servos_by_id.get(servo_id, ()):
            data = read_data(servo, address, length)
            if data is not None:
                replies.append((servo, build_status(servo_id, error_byte(servo), data)))
        if replies:
            slots.append(Slot(tuple(replies)))
    return slots


def execute(packet: Packet, servos: Sequence[VirtualServo]) -> list[Slot]:
    """Run `packet` on the Feetech servos that hear it; return the reply slots in wire order."""
    for servo in servos:
        if packet.servo_id in (servo.servo_id, BROADCAST_ID):
            servo.note_packet()
    if packet.servo_id != BROADCAST_ID:
        return _single(packet, servos)
    if not packet.intact:
        return []
    inst = packet.instruction
    if inst == Instruction.PING:
        replies = tuple((s, build_status(s.servo_id, error_byte(s))) for s in servos)
        return [Slot(replies)] if replies else []
    if inst == Instruction.SYNC_WRITE:
        _sync_write(packet, servos)
    elif inst == Instruction.SYNC_READ:
        return _sync_read(packet, servos)
    elif inst == Instruction.RESTART:
        for servo in servos:
            servo.power_cycle()
    elif inst in _BROADCAST_RUNS:
        for servo in servos:
            _unicast(packet, servo)
    return []
