"""Strict reading of one TOML table: typed fields, ranges, and unknown-key errors with key paths."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from snakebot.errors import ConfigError


class Table:
    """One table of a config file; every read names ``source`` and the dotted key path on error."""

    def __init__(self, source: Path | str, data: Mapping[str, Any], path: str = "") -> None:
        self.source = source
        self.data = data
        self.path = path
        self._seen: set[str] = set()

    def _key(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def error(self, key: str, message: str) -> ConfigError:
        """A ConfigError for ``key`` of this table."""
        return ConfigError(self.source, self._key(key), message)

    def has(self, key: str) -> bool:
        """True if the table sets ``key``."""
        return key in self.data

    def _get(self, key: str, default: Any) -> Any:
        self._seen.add(key)
        if key in self.data:
            return self.data[key]
        if default is _REQUIRED:
            raise self.error(key, "missing (required)")
        return default

    def number(
        self,
        key: str,
        default: Any = None,
        *,
        minimum: float | None = None,
        maximum: float | None = None,
        positive: bool = False,
    ) -> float:
        """A finite float within the given bounds."""
        value = self._get(key, _REQUIRED if default is None else default)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(key, f"expected a number, got {value!r}")
        value = float(value)
        if not math.isfinite(value):
            raise self.error(key, f"expected a finite number, got {value!r}")
        if positive and value <= 0:
            raise self.error(key, f"expected a positive number, got {value!r}")
        if minimum is not None and value < minimum:
            raise self.error(key, f"expected a number >= {minimum}, got {value!r}")
        if maximum is not None and value > maximum:
            raise self.error(key, f"expected a number <= {maximum}, got {value!r}")
        return value

    def integer(
        self,
        key: str,
        default: Any = None,
        *,
        minimum: int | None = None,
        maximum: int | None = None,
        choices: Sequence[int] | None = None,
    ) -> int:
        """An integer within the given bounds or choices."""
        value = self._get(key, _REQUIRED if default is None else default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"expected an integer, got {value!r}")
        if choices is not None and value not in choices:
            raise self.error(key, f"expected one of {list(choices)}, got {value!r}")
        if minimum is not None and value < minimum:
            raise self.error(key, f"expected an integer >= {minimum}, got {value!r}")
        if maximum is not None and value > maximum:
            raise self.error(key, f"expected an integer <= {maximum}, got {value!r}")
        return value

    def text(self, key: str, default: Any = None, *, choices: Sequence[str] | None = None) -> str:
        """A string, optionally one of ``choices``."""
        value = self._get(key, _REQUIRED if default is None else default)
        if not isinstance(value, str):
            raise self.error(key, f"expected a string, got {value!r}")
        if choices is not None and value not in choices:
            raise self.error(key, f"expected one of {list(choices)}, got {value!r}")
        return value

    def table(self, key: str, *, required: bool = True) -> Table:
        """A nested table (an empty one when optional and absent)."""
        value = self._get(key, _REQUIRED if required else {})
        if not isinstance(value, Mapping):
            raise self.error(key, f"expected a table, got {type(value).__name__}")
        return Table(self.source, value, self._key(key))

    def tables(self, key: str) -> list[Table]:
        """A non-empty array of tables (``[[key]]``)."""
        value = self._get(key, _REQUIRED)
        if not isinstance(value, list) or not value:
            raise self.error(key, "expected a non-empty array of tables ([[...]])")
        out = []
        for index, item in enumerate(value):
            if not isinstance(item, Mapping):
                raise ConfigError(self.source, f"{self._key(key)}[{index}]", "expected a table")
            out.append(Table(self.source, item, f"{self._key(key)}[{index}]"))
        return out

    def done(self) -> None:
        """Reject keys nobody read: a typo must not be silently ignored."""
        unknown = sorted(set(self.data) - self._seen)
        if unknown:
            known = ", ".join(sorted(self._seen)) or "none"
            raise self.error(unknown[0], f"unknown key (known keys here: {known})")


_REQUIRED = object()
