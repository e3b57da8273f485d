"""Prepared group transactions for the control loop: built once, no SDK objects made per cycle.

:class:`SyncWritePlan` packs the Sync Write parameters (``[id, data...]`` per servo) with one
precompiled ``struct``; :class:`ReadPlan` keeps one group read of the family's read method
(Fast Sync / Sync / Bulk Read, or one Read per servo) and unpacks every servo's block with one
``struct`` too. Plain ints and tuples, not numpy, on this path: a handful of
small numpy calls costs more than the whole decode when the caches are cold between bus waits.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from snakebot.backends.chain.blocks import Block
from snakebot.backends.chain.links import GroupReader, Link
from snakebot.backends.dynamixel import sdk
from snakebot.families import READ_METHODS
from snakebot.servo_tables import Register, RegisterValueError
from snakebot.servo_tables.table import decode_magnitude

if TYPE_CHECKING:
    from snakebot.backends.chain.transport import Transport

_STRUCT_CODES = {
    (1, False): "B",
    (1, True): "b",
    (2, False): "H",
    (2, True): "h",
    (4, False): "I",
    (4, True): "i",
}

Row = tuple[int, ...]


def block_struct(block: Block, prefix: int = 0) -> struct.Struct:
    """Struct of one servo's block in its byte order (little-endian but on Feetech SCS): one
    code per field, pad bytes for gaps and for ``prefix`` bytes before the block (the status
    byte a Feetech Sync Read keeps in front of each servo's data)."""
    big = any(f.byteorder == "big" for f in block.fields)
    codes, at = [">" if big else "<", "x" * prefix], 0
    for f in block.fields:
        codes.append("x" * (f.offset - at) + _STRUCT_CODES[(f.size, f.signed)])
        at = f.offset + f.size
    codes.append("x" * (block.size - at))
    return struct.Struct("".join(codes))


class SyncWritePlan:
    """A Sync Write of one register to fixed servo IDs, in the ID order given."""

    def __init__(self, transport: Transport, register: Register, ids: Sequence[int]) -> None:
        if not register.writable:
            raise RegisterValueError(f"register {register.key} ({register.address}) is read-only")
        if len(set(ids)) != len(ids) or not ids:
            raise ValueError(f"a sync write needs distinct servo IDs, got {list(ids)}")
        self.register = register
        self.ids = tuple(ids)
        self._transport = transport
        code = _STRUCT_CODES[(register.size, register.signed)]
        order = ">" if register.byteorder == "big" else "<"
        self._packer = struct.Struct(order + ("B" + code) * len(ids))
        self._args: list[int] = [v for i in ids for v in (i, 0)]  # [id, value] per servo
        self._what = f"sync write {register.key}"

    def write(self, values: np.ndarray | Sequence[int], *, checked: bool = True) -> None:
        """Send ``values`` (register units, one int per ID) in one Sync Write.

        ``checked`` validates the count and the register range; the control loop passes False for
        goals it has already clipped inside the joint limits (packing still refuses overflow).
        """
        items = values.tolist() if isinstance(values, np.ndarray) else list(values)
        if checked:
            if len(items) != len(self.ids) or not all(isinstance(v, int) for v in items):
                raise ValueError(f"{self._what}: need {len(self.ids)} integers, got {items!r}")
            low, high = min(items), max(items)
            if low < self.register.minimum or high > self.register.maximum:
                raise RegisterValueError(
                    f"{self._what}: values {low}..{high} exceed "
                    f"{self.register.minimum}..{self.register.maximum}"
                )
        args = self._args
        args[1::2] = items
        try:
            param = self._packer.pack(*args)
        except struct.error as exc:
            raise RegisterValueError(f"{self._what}: {exc}") from exc
        address, size = self.register.address, self.register.size
        # syncWriteTxOnly copies the parameters by slicing, which bytes support like a list.
        link = self._transport.link
        result = self._transport.run(
            self.ids, self._what, lambda: link.sync_write(address, size, param)
        )
        self._transport.check_sent(result, self.ids, self._what)


class ReadPlan:
    """A group read of one block from fixed servo IDs by one of the family's read methods,
    its SDK group object built once.

    ``method`` is one of ``snakebot.families.READ_METHODS``: "fast_sync_read" or "sync_read"
    (one ``GroupSyncRead``; Fast Sync Read only when a read asks ``fast``), "bulk_read" (one
    ``GroupBulkRead`` naming the same block for every ID: Protocol 1.0's only group read), or
    "read" (one Read per servo, each with its own retries: an AX-12A has no group read).
    Every method gives the same rows, retries and SyncReadError naming the silent IDs.
    """

    def __init__(
        self,
        transport: Transport,
        link: Link,
        block: Block,
        ids: Sequence[int],
        method: str,
        single: Callable[[int, Block], dict[str, int]],
    ) -> None:
        if method not in READ_METHODS:
            known = ", ".join(READ_METHODS)
            raise ValueError(f"read method must be one of {known}, got {method!r}")
        self.block = block
        self.ids = tuple(ids)
        self.method = method
        self._transport = transport
        self._link = link
        self._sync: GroupReader | None = None
        self._bulk: sdk.BulkReader | None = None
        if method in ("fast_sync_read", "sync_read"):
            self._sync = link.sync_reader(block.address, block.size, self.ids)
        elif method == "bulk_read":
            self._bulk = link.bulk_reader([(i, block.address, block.size) for i in self.ids])
        elif len(set(self.ids)) != len(self.ids):
            raise ValueError(f"servo IDs appear twice in one read: {list(self.ids)}")
        self._single_read = single
        self._unpacker = block_struct(block)
        prefix = 0 if self._sync is None else self._sync.prefix
        self._sync_unpacker = block_struct(block, prefix)
        self._sync_total = (block.size + prefix) * len(self.ids)
        # (field index, sign bit, magnitude mask) of each sign-magnitude field.
        self._magnitude = [
            (k, f.sign_bit, (1 << f.sign_bit) - 1)
            for k, f in enumerate(block.fields)
            if f.sign_bit is not None
        ]
        self._total = block.size * len(self.ids)
        name = "sync read" if method == "fast_sync_read" else method.replace("_", " ")
        self._what = f"{name} {','.join(block.keys)}"

    def _transact(self, fast: bool) -> list[Row] | None:
        """One group transaction: each ID's field values in ID order, or None to retry."""
        if self._bulk is not None:
            result = self._bulk.transact()
            if result != sdk.COMM_SUCCESS:
                self._transport.retry_or_raise(result, self.ids, self._what)
                return None
            joined = self._bulk.joined()
            if joined is None or len(joined) != self._total:
                return None
            return self._values(list(self._unpacker.iter_unpack(joined)))
        assert self._sync is not None
        reader = self._sync
        result = reader.transact(fast and self.method == "fast_sync_read")
        if result != sdk.COMM_SUCCESS:
            self._transport.retry_or_raise(result, self.ids, self._what)
            return None
        # Every servo's row (``prefix`` status bytes, then the block), or None when one is
        # missing: after a failed read the SDK hands out zeros (reference §1.7).
        buffer = reader.joined()
        # No servo's row can be longer than it should, so the total catches any short one.
        if buffer is None or len(buffer) != self._sync_total:
            return None
        return self._values(list(self._sync_unpacker.iter_unpack(buffer)))

    def _values(self, rows: list[Row]) -> list[Row]:
        """Rows with sign-magnitude fields turned from raw bits into values (a row whose fields
        are all non-negative, every bit inside the magnitude, is its own value: kept as is)."""
        if not self._magnitude:
            return rows
        fields = self._magnitude
        out = []
        for row in rows:
            for k, _, mask in fields:
                if row[k] > mask:
                    break
            else:
                out.append(row)
                continue
            values = list(row)
            for k, bit, _ in fields:
                values[k] = decode_magnitude(values[k], bit)
            out.append(tuple(values))
        return out

    def _single(self, servo_id: int) -> dict[str, int]:
        return self._single_read(servo_id, self.block)

    def read(self, *, fast: bool = False) -> dict[int, dict[str, int]]:
        """``{id: {key: value}}``; SyncReadError names servos silent even when read alone."""
        keys = self.block.keys
        return {
            i: dict(zip(keys, row, strict=True))
            for i, row in zip(self.ids, self.read_rows(fast=fast), strict=True)
        }

    def read_rows(self, *, fast: bool = False) -> list[Row]:
        """One tuple of field values (address order) per servo, in ID order.

        ``fast`` lets a "fast_sync_read" plan use Fast Sync Read (else it sends a Sync Read);
        the other methods ignore it.
        """
        transport = self._transport
        if self._sync is None and self._bulk is None:
            return self._read_each()
        rows = transport.run(self.ids, self._what, lambda: self._transact(fast))
        if rows is not None:  # the common case: first try, no retry machinery
            return rows
        transport.group_retries += transport.retries > 0
        return transport.group_read(
            self.ids,
            lambda: self._transact(fast),
            self._single,
            self._what,
            self._assemble,
            attempts=transport.retries,
        )

    def _read_each(self) -> list[Row]:
        """One Read per servo; unpacked straight into rows while every servo answers, else
        each servo read alone with its retries, naming the silent ones."""
        rows = self._transport.run(self.ids, self._what, self._read_each_once)
        if rows is not None:
            return self._values(rows)
        return self._assemble(self._transport.single_reads(self.ids, self._single, self._what))

    def _read_each_once(self) -> list[Row] | None:
        """The servos' blocks in ID order, or None at the first that fails (no retry here)."""
        link, transport = self._link, self._transport
        read, family = link.read_unguarded, link.family
        address, size, unpack = self.block.address, self.block.size, self._unpacker.unpack
        alerts, rows = transport.alerts, []
        try:  # guard() spelled out: this runs every control cycle
            for servo_id in self.ids:
                data, result, error = read(servo_id, address, size)
                if result != sdk.COMM_SUCCESS or len(data) != size:
                    return None
                if error or servo_id in alerts:
                    if family.instruction_error(error):
                        return None
                    transport.note_condition(servo_id, error)
                rows.append(unpack(bytes(data)))
        except BaseException:
            link.release()
            raise
        return rows

    def _assemble(self, values: dict[int, dict[str, int]]) -> list[Row]:
        keys = self.block.keys
        return [tuple(values[i][k] for k in keys) for i in self.ids]
