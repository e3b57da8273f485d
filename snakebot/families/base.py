"""What a servo family is: one protocol, its instruction set and what it can do, as one class.

A *family* is the wire side of a servo line: the packet format and its SDK packet handler, the
instructions the protocol has, how a status packet's error byte reads, and which group
transactions exist. A *model* (AX-12A, XL430-W250) is data: its control table, tick model, baud
table and datasheet physics (``snakebot.servo_tables``). What a given servo can do is the family's
capabilities narrowed by its model (:meth:`ServoFamily.capabilities`): an AX-12A on Protocol 1.0
has no Bulk Read although the protocol does, an XL430 has no current sensing.

Nothing here imports a vendor SDK; ``snakebot.backends.<vendor>.sdk`` builds the packet handler
for :attr:`ServoFamily.sdk_protocol`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import NamedTuple

from snakebot.servo_tables import ServoTable

READ_METHODS = ("fast_sync_read", "sync_read", "bulk_read", "read")
"""How a cycle's state read goes out, best first: one combined reply, one reply per servo after
one request, one request naming a block per servo, one request per servo."""


@dataclass(frozen=True)
class Capabilities:
    """What one servo model can do on one family's bus (every field a plain yes/no or a list).

    ``read_method`` is the best of :data:`READ_METHODS` the pair has; ``factory_reset_options``
    the Factory Reset variants it has (``all`` also resets ID and baud rate).
    """

    sync_read: bool
    fast_sync_read: bool
    bulk_read: bool
    bus_watchdog: bool
    hardware_error_status: bool
    current_sensing: bool
    reboot: bool
    broadcast_ping: bool
    indirect_addresses: bool
    factory_reset_options: tuple[str, ...]

    @property
    def read_method(self) -> str:
        """The cheapest group read this pair has ("read": one Read per servo)."""
        if self.fast_sync_read:
            return "fast_sync_read"
        if self.sync_read:
            return "sync_read"
        if self.bulk_read:
            return "bulk_read"
        return "read"


class WireCost(NamedTuple):
    """What one transaction costs on the wire: ``wire_bytes`` (10 bit times each at 8N1),
    ``return_delays`` (how many servos wait their Return Delay Time before answering) and
    ``round_trips`` (how many times the host waits for a reply: each costs a USB adapter's latency
    tail)."""

    wire_bytes: int
    return_delays: int
    round_trips: int


class EepromLock(NamedTuple):
    """A write lock in front of a family's EEPROM: the register ``key`` and the values that open
    (``unlocked``) and close (``locked``) it. Feetech's Lock (55 on STS, 48 on SCS): 0 = EEPROM
    writes persist after power-off, 1 (its power-on value) = they are not saved."""

    key: str
    unlocked: int
    locked: int


class ServoFamily(ABC):
    """One servo family's protocol: identity, instruction set, error byte and timing.

    Subclasses are stateless; compare them by :attr:`name`.
    """

    name: str
    """Short name used in robot files and reports, e.g. ``"dynamixel-p1"``."""
    vendor: str
    """The model data's ``family`` value this protocol serves, e.g. ``"dynamixel"``."""
    protocol: float
    """The protocol version a robot file's ``[bus] protocol`` names."""
    sdk_protocol: float
    """What the vendor SDK's packet-handler factory takes for this family."""
    broadcast_id: int
    max_id: int
    broadcast_ping: bool
    """Whether the protocol has a broadcast Ping (every servo answers one request in turn); a
    family without one is searched for by pinging each ID on its own."""
    firmware_address: int
    """Where Firmware Version sits in the protocol's native control tables: the fallback for a
    model number snakebot has no data for (a known model's table says where, e.g. an X-series
    servo in Protocol 1.0 mode keeps its X-series map)."""
    status_overhead_bytes: int
    """Bytes of one status packet beyond its data (header, ID, length, error, checksum)."""
    read_overhead_bytes: int
    """Bytes of one Read instruction packet."""
    condition_bits: int
    """Bits of a status packet's error byte that report the servo's condition (a latched
    hardware error, overload, heat) rather than a fault of the instruction it answers: the data
    that comes with them is valid."""
    resend_error: int
    """The error (after :attr:`condition_bits` are masked off) of a servo that received a
    corrupt instruction: sending it again can help."""
    access_error: int | None
    """The error of a write the servo refused for its state (EEPROM with torque on), if any."""
    factory_reset_takes_option: bool
    """Whether Factory Reset carries a what-to-keep option (else it always resets everything)."""
    byte_order: str = "little"
    """How the family's servos order the bytes of a word on the wire: "little" (Dynamixel,
    Feetech STS) or "big" (Feetech SCS)."""
    eeprom_lock: EepromLock | None = None
    """The lock an EEPROM write must open first and close after (None: no such lock; a
    Dynamixel P1 Lock only ever closes, until power-off)."""
    restart_replies: bool = True
    """Whether a Reboot/Restart instruction is answered (Feetech's Restart 0x08 is not)."""
    framing: str = ""
    """The packet format, where two families share one byte for byte (Feetech's is Dynamixel
    Protocol 1.0's, ``"dynamixel-1.0"``): a ping is then the same packet in both, and a search
    pings each ID once for all of them."""
    calibrates_homing_offset: bool = False
    """Whether ``calibrate`` zeroes each servo itself, writing its Homing Offset so a straight
    joint reads the centre tick (Feetech STS: the position wraps at 0/4095 and the angle limits
    cannot span the wrap). False: the Homing Offset stays 0, the offset lives in the robot file."""

    @property
    def label(self) -> str:
        """How messages name the family's protocol, e.g. "Protocol 1.0"."""
        return f"Protocol {self.protocol:.1f}"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ServoFamily) and other.name == self.name

    def __hash__(self) -> int:
        return hash(self.name)

    def __repr__(self) -> str:
        return f"<servo family {self.name}>"

    def speaks(self, table: ServoTable) -> bool:
        """Whether servos of this model can run this family's protocol at all."""
        return table.family == self.vendor and self.protocol in table.protocols

    def instruction_error(self, error: int) -> int:
        """The part of a status error byte that says the instruction failed (0: it worked)."""
        return error & ~self.condition_bits & 0xFF

    @abstractmethod
    def capabilities(self, table: ServoTable) -> Capabilities:
        """What a servo of model ``table`` can do on this family's bus."""

    @abstractmethod
    def status_errors(self, error: int) -> tuple[str, ...]:
        """Names of the faults a status packet's error byte reports, e.g. ("overload",)."""

    @abstractmethod
    def read_cost(self, method: str, n_servos: int, length: int) -> WireCost:
        """What reading ``length`` bytes from each of ``n_servos`` by ``method`` (one of
        :data:`READ_METHODS`) costs on the wire; ValueError for a method the family lacks."""

    @abstractmethod
    def sync_write_bytes(self, n_servos: int, length: int) -> int:
        """Bytes of one Sync Write of ``length`` data bytes to ``n_servos``."""
