"""A Dynamixel bus with registers by name, typed errors, bounded retries and the SDK traps handled.

Registers are named as in ``snakebot.servo_tables`` (``"present_position"``); values are register
units (ticks, signed where the register is). Errors and retries: see ``transport.py``.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from types import TracebackType
from typing import Any, TypeVar

from snakebot.backends.chain import links
from snakebot.backends.chain.blocks import Block, encode_checked, encode_rows, resolve_block
from snakebot.backends.chain.faults import ServoStatusError
from snakebot.backends.chain.plans import ReadPlan, SyncWritePlan
from snakebot.backends.chain.transport import Transport
from snakebot.backends.dynamixel import sdk
from snakebot.config.ports import check_port
from snakebot.errors import BusError
from snakebot.families import Capabilities, ServoFamily, family_for
from snakebot.servo_tables import ServoTable, table_for_model

FACTORY_RESET_OPTIONS = {"all": 0xFF, "keep_id": 0x01, "keep_id_baud": 0x02}

Keys = str | Sequence[str]
T = TypeVar("T")


class ServoBus:
    """One serial port with a chain of Dynamixel servos of one model, addressed by ID.

    ``model`` picks the control table that register names resolve in (X-series servos share
    addresses); ``family`` the protocol spoken (``snakebot.families``; default
    ``family_for(table, protocol)``, ConfigError if the model cannot speak ``protocol``). What the
    bus does per cycle follows the pair's :attr:`capabilities`: group reads go out by its
    ``read_method`` (Fast Sync / Sync / Bulk Read, or one Read per servo).
    ``port_handler_factory`` builds the SDK port handler from the port name, e.g. the emulator's
    ``EmulatedPortHandler``; default: the family's vendor SDK's (``links.port_handler_for``).
    The link follows the family's vendor (``links.link_for``): the Dynamixel SDK, or Feetech's
    ``scservo_sdk`` for a Feetech servo; everything above it is the same. ``clock`` (s) stamps
    ``last_instruction_s``. ``port`` must pass ``snakebot.config.ports.check_port`` (a device path
    or a ``dxlemu://`` URL), else ConfigError before anything is opened.
    """

    def __init__(
        self,
        port: str,
        baud: int,
        *,
        protocol: float | None = None,
        model: str | int = "XL430-W250",
        family: ServoFamily | None = None,
        port_handler_factory: Callable[[str], Any] | None = None,
        retries: int = 2,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.port = port
        self.baud = baud
        self.table: ServoTable = table_for_model(model)
        self.family: ServoFamily = family or family_for(self.table, protocol)
        self.protocol = self.family.protocol
        self.capabilities: Capabilities = self.family.capabilities(self.table)
        """What this model can do on this family's bus (read method, watchdog, ...)."""
        check_port(port)  # device paths and dxlemu:// only: no socket://, spy://?file=, ...
        family = self.family
        handler = (
            port_handler_factory(port)
            if port_handler_factory
            else links.port_handler_for(port, family)
        )
        self._link: links.Link = links.link_for(handler, family)
        self.transport = Transport(port, self._link, retries, clock)
        self._read_plans: dict[tuple[Block, tuple[int, ...], str], ReadPlan] = {}

    @property
    def retries(self) -> int:
        """Extra attempts after a timeout or corrupt packet (settable, e.g. 0 for a fast scan)."""
        return self.transport.retries

    @retries.setter
    def retries(self, count: int) -> None:
        if count < 0:
            raise ValueError(f"retries must be >= 0, got {count}")
        self.transport.retries = count

    def run(self, ids: Sequence[int], what: str, op: Callable[[], T]) -> T:
        """Run one raw SDK call (no retries): OSError becomes a BusError naming port and IDs."""
        return self.transport.run(ids, what, op)

    @property
    def retry_counts(self) -> Counter[int]:
        """Retried transactions per servo ID (timeouts, corrupt packets)."""
        return self.transport.retry_counts

    @property
    def group_retries(self) -> int:
        """Group reads (Sync / Fast Sync / Bulk Read) sent again after a failure."""
        return self.transport.group_retries

    @property
    def group_fallbacks(self) -> int:
        """Group reads that failed and were served by single reads instead."""
        return self.transport.group_fallbacks

    @property
    def alerts(self) -> set[int]:
        """IDs whose last status packet reported a servo condition: the Alert bit (a latched
        hardware error, Protocol 2.0) or Protocol 1.0's overload, overheating, input voltage."""
        return self.transport.alerts

    @property
    def conditions(self) -> dict[int, int]:
        """``{id: condition bits}`` of the servos in :attr:`alerts` (the status error byte's
        ``family.condition_bits``; ``family.status_errors`` names them)."""
        return self.transport.conditions

    @property
    def vanished(self) -> BusError | None:
        """The BusError of the first OS error on the port, once it vanished; None while it works."""
        return self.transport.vanished

    @property
    def last_instruction_s(self) -> float:
        """``clock()`` when the last instruction was sent."""
        return self.transport.last_instruction_s

    # -- lifecycle ---------------------------------------------------------------------------
    def open(self) -> None:
        """Open the port at the bus baud rate; BusError if the port or rate is unusable."""
        try:
            ok = self._link.open(self.baud)
        except sdk.PORT_ERRORS as exc:
            raise BusError(
                self.port,
                [],
                f"cannot open the port: {exc}. Check the adapter is plugged in and "
                "the name (ls /dev/ttyUSB* /dev/serial/by-id/; COMx on Windows)",
            ) from exc
        if not ok:
            raise BusError(
                self.port,
                [],
                f"the {self.family.vendor} SDK refuses {self.baud} bit/s (dynamixel_sdk "
                "supports up to 4 Mbps, 4.5 Mbps needs a custom port handler; Feetech's baud "
                "table ends at 1 Mbps)",
            )

    def close(self) -> None:
        """Close the port (idempotent)."""
        self._link.close()

    @property
    def is_open(self) -> bool:
        """Whether the port is open."""
        return bool(self._link.port.is_open)

    def __enter__(self) -> ServoBus:
        self.open()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    # -- single servos -------------------------------------------------------------------------
    def ping(self, servo_id: int) -> int:
        """The servo's model number; BusError if it does not answer after the retries."""

        def op() -> tuple[int, int, list[int]]:
            model, result, error = self._link.ping(servo_id)
            return result, error, [model]

        return self.transport.unicast(servo_id, "ping", op)[0]

    def ping_all(self, ids: Sequence[int]) -> dict[int, int]:
        """``{id: model number}`` for the IDs that answer a ping; silent IDs are left out."""
        found = {}
        for servo_id in ids:
            try:
                found[servo_id] = self.ping(servo_id)
            except ServoStatusError:
                raise
            except BusError:
                continue
        return found

    def broadcast_ping(self) -> dict[int, tuple[int, int]]:
        """``{id: (model number, firmware version)}`` of every servo on the bus.

        Slow: the SDK always waits its whole window (about 0.8 s at 1 Mbps).
        """
        found, result = self.transport.run([], "broadcast ping", self._link.broadcast_ping)
        if result not in (sdk.COMM_SUCCESS, sdk.COMM_RX_TIMEOUT, sdk.COMM_RX_CORRUPT):
            raise self.transport.fail(result, [], "broadcast ping")
        return {i: (int(v[0]), int(v[1])) for i, v in found.items()}

    def read(self, servo_id: int, key: str) -> int:
        """One register of one servo (signed where the register is)."""
        return self.read_block(servo_id, key)[self.table[key].key]

    def read_block(self, servo_id: int, keys: Keys | Block) -> dict[str, int]:
        """Several registers of one servo in one Read of the block covering them."""
        block = keys if isinstance(keys, Block) else resolve_block(self.table, keys)

        def op() -> tuple[int, int, list[int]]:
            data, result, error = self._link.read(servo_id, block.address, block.size)
            if result == sdk.COMM_SUCCESS and len(data) != block.size:
                result = sdk.COMM_RX_CORRUPT
            return result, error, data

        data = self.transport.unicast(servo_id, f"read {','.join(block.keys)}", op)
        return block.decode(data)

    def write(self, servo_id: int, key: str, value: int) -> None:
        """Write one register (range-checked) and wait for the servo's status."""
        register = self.table[key]
        data = encode_checked(register, value)

        def op() -> tuple[int, int, list[int]]:
            result, error = self._link.write(servo_id, register.address, data)
            return result, error, []

        if servo_id == sdk.BROADCAST_ID:
            self.transport.run([servo_id], f"write {register.key}", op)
            return
        what = f"write {register.key}={value}"
        self.transport.unicast(servo_id, what, op, eeprom=register.eeprom)

    def reboot(self, servo_id: int) -> None:
        """Reboot one servo (clears a latched hardware error; torque comes back off)."""

        def op() -> tuple[int, int, list[int]]:
            result, error = self._link.reboot(servo_id)
            return result, error, []

        self.transport.unicast(servo_id, "reboot", op, accept_alert=True)
        self.transport.alerts.discard(servo_id)

    def factory_reset(self, servo_id: int, *, keep: str = "keep_id_baud") -> None:
        """Reset one servo's control table; ``keep`` is "keep_id_baud", "keep_id" or "all".

        ValueError for a ``keep`` the model's family does not have (Protocol 1.0 always resets
        everything, ID and baud rate included: it is never sent as a milder reset).
        """
        if keep not in self.capabilities.factory_reset_options:
            have = ", ".join(self.capabilities.factory_reset_options)
            raise ValueError(
                f"{self.table.model} on {self.family.name} has no factory reset "
                f"{keep!r} (only {have}: it resets ID and baud rate too)"
            )
        option = FACTORY_RESET_OPTIONS[keep]

        def op() -> tuple[int, int, list[int]]:
            result, error = self._link.factory_reset(servo_id, option)
            return result, error, []

        self.transport.unicast(servo_id, f"factory reset ({keep})", op, accept_alert=True)

    # -- groups --------------------------------------------------------------------------------
    def sync_write(self, keys: Keys, values: Mapping[int, int | Sequence[int]]) -> None:
        """One Sync Write of the registers ``keys`` (contiguous) to ``{id: value(s)}``; no reply."""
        block = resolve_block(self.table, keys)
        rows = encode_rows(block, self.table, values)
        writer = self._link.sync_writer(block.address, block.size, rows)
        ids, what = [i for i, _ in rows], f"sync write {','.join(block.keys)}"
        self.transport.check_sent(self.transport.run(ids, what, writer.send), ids, what)

    def sync_read(
        self, keys: Keys | Block, ids: Sequence[int], *, fast: bool = False
    ) -> dict[int, dict[str, int]]:
        """One group read of the block covering ``keys`` from ``ids``: ``{id: {key: value}}``.

        It goes out by the bus's read method (:meth:`sync_read_plan`); ``fast`` allows Fast
        Sync Read where the model has it. Raises SyncReadError naming the IDs that stay silent
        after the retries.
        """
        return self.sync_read_plan(keys, ids).read(fast=fast)

    def bulk_read(self, requests: Mapping[int, Keys]) -> dict[int, dict[str, int]]:
        """One Bulk Read of a different block per servo: ``{id: {key: value}}``."""
        blocks = {i: resolve_block(self.table, k) for i, k in requests.items()}
        reader = self._link.bulk_reader([(i, b.address, b.size) for i, b in blocks.items()])
        ids = list(blocks)

        def attempt() -> dict[int, dict[str, int]] | None:
            result = reader.transact()
            if result != sdk.COMM_SUCCESS:
                self.transport.retry_or_raise(result, ids, "bulk read")
                return None
            out = {}
            for i, b in blocks.items():
                data = reader.data(i)
                if not reader.available(i, b.address, b.size) or len(data) != b.size:
                    return None
                out[i] = b.decode(data)
            return out

        return self.transport.group_read(
            ids, attempt, lambda i: self.read_block(i, blocks[i]), "bulk read", dict
        )

    def sync_read_plan(
        self, keys: Keys | Block, ids: Sequence[int], *, method: str | None = None
    ) -> ReadPlan:
        """A reusable group read of one block from fixed IDs (cached per block, IDs, method).

        ``method`` (one of ``snakebot.families.READ_METHODS``) defaults to the capabilities'
        ``read_method``; benchmarks and tests pick a slower one on purpose.
        """
        block = keys if isinstance(keys, Block) else resolve_block(self.table, keys)
        chosen = method or self.capabilities.read_method
        cache_key = (block, tuple(ids), chosen)
        plan = self._read_plans.get(cache_key)
        if plan is None:
            plan = ReadPlan(self.transport, self._link, block, ids, chosen, self.read_block)
            self._read_plans[cache_key] = plan
        return plan

    def sync_write_plan(self, key: str, ids: Sequence[int]) -> SyncWritePlan:
        """A reusable Sync Write of one register to fixed IDs with a preallocated parameter list
        (every family has Sync Write)."""
        return SyncWritePlan(self.transport, self.table[key], ids)
