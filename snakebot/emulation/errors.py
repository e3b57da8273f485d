"""Errors of the emulated bus (all under `snakebot.errors.SnakebotError`)."""

from __future__ import annotations

from snakebot.errors import SnakebotError


class EmulationError(SnakebotError, ValueError):
    """The emulator was set up or addressed wrongly: unknown servo, bad ID, unknown chain name."""
