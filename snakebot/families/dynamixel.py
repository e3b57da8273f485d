"""The two Dynamixel families: Protocol 2.0 (X, MX 2.0 firmware) and Protocol 1.0 (AX, MX, X).

References: e-Manual ``docs/en/dxl/protocol1.md`` and ``protocol2.md``; the SDK's
``protocol1_packet_handler.py`` (no Sync Read, Reboot, broadcast Ping or Bulk Write in 1.0);
/work/shared/reference/servo-families.md §3-5 and dynamixel.md §1.
"""

from __future__ import annotations

from snakebot.families.base import Capabilities, ServoFamily, WireCost
from snakebot.servo_tables import ServoTable

P1_ERROR_BITS = (
    (0x01, "input voltage"),
    (0x02, "angle limit"),
    (0x04, "overheating"),
    (0x08, "range"),
    (0x10, "checksum"),
    (0x20, "overload"),
    (0x40, "instruction"),
)
"""Protocol 1.0 status error byte, bit by bit (bit 7 is always 0)."""

P2_ERRORS = {
    0x01: "result fail",
    0x02: "instruction",
    0x03: "crc",
    0x04: "data range",
    0x05: "data length",
    0x06: "data limit",
    0x07: "access",
}
"""Protocol 2.0 status error numbers (bits 0-6); bit 7 is the Alert (a latched hardware error)."""


class DynamixelProtocol2(ServoFamily):
    """Dynamixel Protocol 2.0: CRC-16 packets, Sync/Fast Sync/Bulk Read, Reboot, Bus Watchdog."""

    name = "dynamixel-p2"
    vendor = "dynamixel"
    framing = "dynamixel-2.0"
    protocol = 2.0
    sdk_protocol = 2.0
    broadcast_id = 0xFE
    max_id = 252
    broadcast_ping = True
    firmware_address = 6  # Model Number 0-1, Model Information 2-5, Firmware Version 6
    status_overhead_bytes = 11  # FF FF FD 00, ID, LEN(2), 0x55, ERR, CRC(2)
    read_overhead_bytes = 14
    condition_bits = 0x80  # Alert: read Hardware Error Status (70)
    resend_error = 0x03  # CRC error
    access_error = 0x07
    factory_reset_takes_option = True

    def capabilities(self, table: ServoTable) -> Capabilities:
        """Every group read; watchdog, hardware error and current sensing where the table has
        the register; Fast Sync Read where the model's firmware has it."""
        return Capabilities(
            sync_read=True,
            fast_sync_read=table.specs.fast_sync_read,
            bulk_read=True,
            bus_watchdog="bus_watchdog" in table,
            hardware_error_status="hardware_error_status" in table,
            current_sensing="present_current" in table,
            reboot=True,
            broadcast_ping=self.broadcast_ping,
            indirect_addresses=bool(table.specs.indirect_banks),
            factory_reset_options=("keep_id_baud", "keep_id", "all"),
        )

    def status_errors(self, error: int) -> tuple[str, ...]:
        """The error number (bits 0-6) and the Alert bit, by name."""
        names = [P2_ERRORS.get(error & 0x7F, f"error {error & 0x7F}")] if error & 0x7F else []
        if error & 0x80:
            names.append("alert")
        return tuple(names)

    def read_cost(self, method: str, n_servos: int, length: int) -> WireCost:
        """Sync Read: request 14 + N, then N replies of 11 + L, each after its Return Delay; Fast
        Sync Read: the same request and one combined reply of 8 + N (L + 4), one Return Delay;
        Bulk Read: request 10 + 5 N; Read: a 14-byte request and a reply per servo, a round trip
        each (e-Manual protocol2.md packet layouts, unstuffed)."""
        n, reply = n_servos, self.status_overhead_bytes + length
        if method == "fast_sync_read":
            return WireCost(14 + n + 8 + n * (length + 4), 1, 1)
        if method == "sync_read":
            return WireCost(14 + n + n * reply, n, 1)
        if method == "bulk_read":
            return WireCost(10 + 5 * n + n * reply, n, 1)
        if method == "read":
            return WireCost(n * (self.read_overhead_bytes + reply), n, n)
        raise ValueError(
            f"unknown read method {method!r}; known: fast_sync_read, sync_read, bulk_read, read"
        )

    def sync_write_bytes(self, n_servos: int, length: int) -> int:
        """14 bytes of header, address and length, then ID + data per servo."""
        return 14 + n_servos * (1 + length)


class DynamixelProtocol1(ServoFamily):
    """Dynamixel Protocol 1.0: checksum packets, Sync Write and Bulk Read, a bit-per-fault error
    byte, no Sync Read, Reboot, broadcast Ping or Bus Watchdog instruction."""

    name = "dynamixel-p1"
    vendor = "dynamixel"
    framing = "dynamixel-1.0"
    protocol = 1.0
    sdk_protocol = 1.0
    broadcast_id = 0xFE
    max_id = 253
    broadcast_ping = False  # the SDK's Protocol 1.0 broadcastPing is COMM_NOT_AVAILABLE
    firmware_address = 2  # AX/MX/RX: Model Number 0-1, Firmware Version 2 (e-Manual)
    status_overhead_bytes = 6  # FF FF, ID, LEN, ERR, CHK
    read_overhead_bytes = 8
    # Input voltage, overheating, overload: the servo's state, reported in every status packet
    # while it lasts (e-Manual protocol1.md "Status Packet"); the Alarm Shutdown register decides
    # which of them also turn its torque off.
    condition_bits = 0x25
    resend_error = 0x10  # checksum error
    access_error = None
    factory_reset_takes_option = False

    def capabilities(self, table: ServoTable) -> Capabilities:
        """Bulk Read where the model has it (MX, X in 1.0 mode; not AX); the Bus Watchdog and
        Hardware Error Status registers where the (X) table has them below address 256."""

        def reachable(key: str) -> bool:
            return key in table and table[key].address + table[key].size <= 256

        return Capabilities(
            sync_read=False,
            fast_sync_read=False,
            bulk_read=table.specs.bulk_read,
            bus_watchdog=reachable("bus_watchdog"),
            hardware_error_status=reachable("hardware_error_status"),
            current_sensing=reachable("present_current"),
            reboot=False,
            broadcast_ping=self.broadcast_ping,
            indirect_addresses=False,
            factory_reset_options=("all",),
        )

    def status_errors(self, error: int) -> tuple[str, ...]:
        """Every set bit of the error byte, by name (e-Manual protocol1.md)."""
        return tuple(name for bit, name in P1_ERROR_BITS if error & bit)

    def read_cost(self, method: str, n_servos: int, length: int) -> WireCost:
        """Bulk Read: request 3 N + 7, then N replies of 6 + L, each after its Return Delay, one
        round trip; Read: an 8-byte request and a 6 + L reply per servo, a round trip each."""
        n, reply = n_servos, self.status_overhead_bytes + length
        if method == "bulk_read":
            return WireCost(3 * n + 7 + n * reply, n, 1)
        if method == "read":
            return WireCost(n * (self.read_overhead_bytes + reply), n, n)
        raise ValueError(f"Protocol 1.0 has no {method.replace('_', ' ')}")

    def sync_write_bytes(self, n_servos: int, length: int) -> int:
        """8 bytes of header, address and length, then ID + data per servo."""
        return 8 + n_servos * (1 + length)
