"""The two Feetech families: STS/SMS (magnetic encoder, little-endian words, Sync Read) and SCS
(potentiometer, big-endian words, no Sync Read).

Both speak Feetech's FT-SCS protocol, whose framing is Dynamixel Protocol 1.0's byte for byte
(``FF FF ID LEN INST params CHK``) with its own instruction set: PING, READ, WRITE, REG_WRITE,
ACTION, 0x06 parameter recovery (all but the ID), 0x08 restart (no reply), 0x0A status reset,
0x0B position calibration, 0x82 SYNC_READ (STS only; replies in request order), 0x83 SYNC_WRITE.
No Bulk Read, no broadcast ping scan ("cannot be used when multiple servos are connected"), no bus
watchdog, no hardware error register: the status byte's bits report the servo's condition.

References: ftservo/ftservo-wiki docs/en/reference/protocol/ft-scs.md (packets, instructions),
memory-sts.md / memory-scscl.md (status bits §3.2, Lock); ftservo/FTServo_Python (the SDK:
``sms_sts`` protocol_end 0, ``scscl`` 1, ERRBIT_* constants); /work/shared/reference/
servo-families.md §1, §5.
"""

from __future__ import annotations

from snakebot.families.base import Capabilities, EepromLock, ServoFamily, WireCost
from snakebot.servo_tables import ServoTable

FEETECH_STATUS_BITS = (
    (0x01, "input voltage"),
    (0x02, "magnetic encoder"),
    (0x04, "overheating"),
    (0x08, "overcurrent"),
    (0x20, "overload"),
)
"""The status byte (and Servo Status register 65), bit by bit: FTServo_Python ERRBIT_VOLTAGE,
ERRBIT_ANGLE, ERRBIT_OVERHEAT, ERRBIT_OVERELE, ERRBIT_OVERLOAD; memory-sts.md §3.2."""

_CONDITION_BITS = 0x2F
_LOCK = EepromLock("lock", unlocked=0, locked=1)


class _Feetech(ServoFamily):
    """What STS and SCS share: the FT-SCS packets, status byte and timing."""

    vendor = "feetech"
    framing = "dynamixel-1.0"  # FF FF ID LEN INST params CHK, the same checksum (ft-scs.md)
    broadcast_id = 0xFE
    max_id = 253  # 0x00..0xFD (ft-scs.md); the SDK's MAX_ID is 0xFC
    broadcast_ping = False
    firmware_address = 0  # Firmware major version 0, minor 1 (memory-sts.md §2.1)
    status_overhead_bytes = 6  # FF FF, ID, LEN, ERR, CHK
    read_overhead_bytes = 8  # FF FF, ID, LEN, 0x02, address, length, CHK
    # Every defined bit is the servo's condition (voltage, encoder, heat, current, load); no bit
    # says the instruction failed, and the data that comes with them is valid.
    condition_bits = _CONDITION_BITS
    # A corrupt instruction is not answered (no checksum bit): it times out and is retried as such.
    resend_error = 0
    access_error = None
    factory_reset_takes_option = False  # 0x06 always keeps the ID and restores the rest
    eeprom_lock = _LOCK
    restart_replies = False
    has_sync_read = True
    """Whether the family has SYNC_READ (0x82): STS yes, SCS no."""

    def status_errors(self, error: int) -> tuple[str, ...]:
        """Every set bit of the status byte, by name (bits 4, 6 as "bit N")."""
        names = [name for bit, name in FEETECH_STATUS_BITS if error & bit]
        names += [f"bit {n}" for n in (4, 6, 7) if error & (1 << n)]
        return tuple(names)

    def _capabilities(self, table: ServoTable, *, sync_read: bool) -> Capabilities:
        return Capabilities(
            sync_read=sync_read,
            fast_sync_read=False,
            bulk_read=False,
            bus_watchdog=False,
            hardware_error_status=False,
            current_sensing="present_current" in table,
            reboot=False,  # Restart (0x08) sends no status packet to confirm it
            broadcast_ping=self.broadcast_ping,
            indirect_addresses=False,
            factory_reset_options=("keep_id",),
        )

    def read_cost(self, method: str, n_servos: int, length: int) -> WireCost:
        """Sync Read: request 8 + N (``FF FF FE N+4 82 addr L ids CHK``), then N replies of 6 + L,
        each after its Return Delay, one round trip; Read: an 8-byte request and a 6 + L reply
        per servo, a round trip each (ft-scs.md packet layouts)."""
        n, reply = n_servos, self.status_overhead_bytes + length
        if method == "sync_read" and self.has_sync_read:
            return WireCost(8 + n + n * reply, n, 1)
        if method == "read":
            return WireCost(n * (self.read_overhead_bytes + reply), n, n)
        raise ValueError(f"{self.name} has no {method.replace('_', ' ')}")

    def sync_write_bytes(self, n_servos: int, length: int) -> int:
        """8 bytes of header, address and length, then ID + data per servo (LEN = (L+1)·N + 4)."""
        return 8 + n_servos * (1 + length)


class FeetechSTS(_Feetech):
    """Feetech STS/SMS servos (STS3215, STS3250): little-endian words, Sync Read 0x82."""

    name = "feetech-sts"
    label = "Feetech STS"
    protocol = 0.0
    sdk_protocol = 0.0  # FTServo_Python sms_sts: protocol_end 0
    byte_order = "little"
    # Calibrate writes Position Offset (31) so the straight joint reads 2048: the 0/4095 wrap
    # then lies behind the joint, where no angle limit or goal reaches (huggingface/lerobot
    # calibrates the same register; Present = Actual - Offset).
    calibrates_homing_offset = True

    def capabilities(self, table: ServoTable) -> Capabilities:
        """Sync Read; current sensing where the table has Present Current (69)."""
        return self._capabilities(table, sync_read=True)


class FeetechSCS(_Feetech):
    """Feetech SCS servos (SCS0009, SCS15): big-endian words, no Sync Read (FTServo_Python's
    ``scscl`` has no GroupSyncRead; LeRobot refuses it on protocol 1), one READ per servo."""

    name = "feetech-scs"
    label = "Feetech SCS"
    protocol = 1.0
    sdk_protocol = 1.0  # FTServo_Python scscl: protocol_end 1
    byte_order = "big"
    has_sync_read = False

    def capabilities(self, table: ServoTable) -> Capabilities:
        """No group read at all: the chain reads each servo in turn."""
        return self._capabilities(table, sync_read=False)
