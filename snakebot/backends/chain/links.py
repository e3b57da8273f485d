"""Which link a chain talks through: by the servo family's vendor, never by a protocol number.

A *link* is one opened port plus its vendor SDK's packet handler, with one method surface
(:class:`Link`): ``snakebot.backends.dynamixel.sdk.SdkLink`` for Dynamixel servos (the only
importer of ``dynamixel_sdk``), ``snakebot.backends.feetech.sdk.FeetechLink`` for Feetech (the
only importer of ``scservo_sdk``). The bus, read plans, stopping and supervision are written
against :class:`Link` and so are shared. A vendor's SDK module is imported only when a chain of
its servos is opened, so a Dynamixel user never imports the Feetech SDK.
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from contextlib import AbstractContextManager
from typing import Any, Protocol

from snakebot.errors import ConfigError
from snakebot.families import ServoFamily

LINK_MODULES = {
    "dynamixel": "snakebot.backends.dynamixel.sdk",
    "feetech": "snakebot.backends.feetech.sdk",
}
"""The SDK module of each vendor: ``port_handler_for(port)`` and ``link(handler, family)``."""


class GroupReader(Protocol):
    """A reusable Sync Read of one block (the SDK's GroupSyncRead)."""

    def transact(self, fast: bool) -> int:
        """Run one read; the result code."""

    def available(self, servo_id: int) -> bool:
        """Whether the last read holds fresh data for ``servo_id``."""

    def data(self, servo_id: int) -> Sequence[int]:
        """Raw block bytes of ``servo_id`` from the last read."""

    prefix: int
    """Bytes in front of each servo's block in :meth:`joined` (Feetech: the status byte)."""

    def joined(self) -> bytearray | None:
        """Every servo's row of the last read in ID order, or None when one is missing."""


class GroupWriter(Protocol):
    """A Sync Write of one block (the SDK's GroupSyncWrite)."""

    def send(self) -> int:
        """Transmit; the result code."""


class Link(Protocol):
    """What the chain uses of a vendor link; every result is a ``dynamixel.sdk.COMM_*`` code."""

    port: Any
    family: ServoFamily

    def guard(self) -> AbstractContextManager[None]:
        """Clear the SDK's busy flag if an exception escapes."""

    def release(self) -> None:
        """Force the busy flag off."""

    def open(self, baud: int) -> bool:
        """Open the port at ``baud``; False if the rate is refused."""

    def close(self) -> None:
        """Close the port (idempotent)."""

    @property
    def port_name(self) -> str:
        """The name the port was opened with."""

    def result_text(self, result: int) -> str:
        """Text for a result code."""

    def error_text(self, error: int) -> str:
        """Text for a status error byte."""

    def ping(self, servo_id: int) -> tuple[int, int, int]:
        """(model number, result, error byte)."""

    def broadcast_ping(self) -> tuple[dict[int, list[int]], int]:
        """({id: [model number, firmware]}, result)."""

    def reboot(self, servo_id: int) -> tuple[int, int]:
        """(result, error byte)."""

    def factory_reset(self, servo_id: int, option: int) -> tuple[int, int]:
        """(result, error byte)."""

    def read(self, servo_id: int, address: int, length: int) -> tuple[list[int], int, int]:
        """(data bytes, result, error byte)."""

    def read_unguarded(
        self, servo_id: int, address: int, length: int
    ) -> tuple[list[int], int, int]:
        """:meth:`read` for a loop that guards itself."""

    def write(self, servo_id: int, address: int, data: bytes) -> tuple[int, int]:
        """(result, error byte)."""

    def sync_write(self, address: int, length: int, param: list[int] | bytes) -> int:
        """Send prepared Sync Write parameters; the result code."""

    def sync_writer(self, address: int, size: int, rows: Sequence[tuple[int, bytes]]) -> Any:
        """A :class:`GroupWriter` of one block."""

    def sync_reader(self, address: int, size: int, ids: Sequence[int]) -> Any:
        """A :class:`GroupReader` of one block."""

    def bulk_reader(self, blocks: Sequence[tuple[int, int, int]]) -> Any:
        """A Bulk Read of one block per servo (Dynamixel only)."""


def _module(family: ServoFamily) -> Any:
    name = LINK_MODULES.get(family.vendor)
    if name is None:
        known = ", ".join(LINK_MODULES)
        raise ConfigError(
            "family", family.name, f"no servo bus for vendor {family.vendor!r}; known: {known}"
        )
    return importlib.import_module(name)


def port_handler_for(port: str, family: ServoFamily) -> Any:
    """The vendor SDK's port handler for ``port`` (a device path or a registered URL)."""
    handler = _module(family).port_handler_for(port)
    return handler


def link_for(handler: Any, family: ServoFamily) -> Link:
    """The vendor link of ``family`` over an opened-or-not port handler."""
    link: Link = _module(family).link(handler, family)
    return link
