"""Strict reading of TOML files and tables: typed fields, ranges, unknown keys, key-path errors."""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from snakebot.config.bounds import Bounds
from snakebot.config.input_file import (
    MAX_CONFIG_BYTES,
    MAX_NAME_CHARS,
    MAX_TEXT_CHARS,
    read_input,
    text_problem,
)
from snakebot.errors import ConfigError


def read_toml(path: Path) -> dict[str, Any]:
    """A TOML file's top-level table; ConfigError naming the file if it cannot be read, is not
    a regular file of at most MAX_CONFIG_BYTES, is not UTF-8 text (a binary file, another
    encoding), is not valid TOML, or nests too deeply for the parser."""
    data = read_input(path, what="TOML config file", limit_bytes=MAX_CONFIG_BYTES)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(
            path, "", f"not UTF-8 text (byte {exc.start}: {exc.reason}); a config file is TOML text"
        ) from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(path, "", f"not valid TOML: {exc}") from exc
    except RecursionError:
        raise ConfigError(path, "", "arrays or tables nested too deeply to read") from None
    except ValueError as exc:  # e.g. an integer of more digits than Python converts
        raise ConfigError(path, "", f"not valid TOML: {exc}") from None


def shown_key(key: str) -> str:
    """A key as an error message may print it: escaped when it holds control or bidirectional
    characters, shortened when it is long."""
    if text_problem(key, max_chars=MAX_NAME_CHARS) is None:
        return key
    text = ascii(key)
    return text if len(text) <= MAX_NAME_CHARS else f"{text[:MAX_NAME_CHARS]}... ({len(key)} chars)"


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
        within: Bounds | None = None,
    ) -> float:
        """A finite float within the given bounds (``within``: a documented range)."""
        value = self._get(key, _REQUIRED if default is None else default)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(key, f"expected a number, got {_short(value)}")
        try:
            value = float(value)
        except OverflowError:  # an integer beyond any float
            raise self.error(key, f"expected a finite number, got {_short(value)}") from None
        if not math.isfinite(value):
            raise self.error(key, f"expected a finite number, got {value!r}")
        if within is not None and not within.contains(value):
            raise self.error(
                key, f"expected a number in {within.describe()} ({within.why}), got {value!r}"
            )
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
        within: Bounds | None = None,
    ) -> int:
        """An integer within the given bounds or choices (``within``: a documented range)."""
        value = self._get(key, _REQUIRED if default is None else default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"expected an integer, got {_short(value)}")
        if within is not None and not within.contains(value):
            raise self.error(
                key, f"expected an integer in {within.describe()} ({within.why}), got {value!r}"
            )
        if choices is not None and value not in choices:
            raise self.error(key, f"expected one of {list(choices)}, got {_short(value)}")
        if minimum is not None and value < minimum:
            raise self.error(key, f"expected an integer >= {minimum}, got {value!r}")
        if maximum is not None and value > maximum:
            raise self.error(key, f"expected an integer <= {maximum}, got {value!r}")
        return value

    def text(
        self,
        key: str,
        default: Any = None,
        *,
        choices: Sequence[str] | None = None,
        max_chars: int = MAX_TEXT_CHARS,
    ) -> str:
        """A non-empty string of at most ``max_chars`` characters without control, format or
        bidirectional characters (snakebot.config.input_file.text_problem), optionally one of
        ``choices``."""
        value = self._get(key, _REQUIRED if default is None else default)
        if not isinstance(value, str):
            raise self.error(key, f"expected a string, got {_short(value)}")
        if not value.strip():
            raise self.error(key, f"expected a non-empty string, got {_short(value)}")
        problem = text_problem(value, max_chars=max_chars)
        if problem is not None:
            raise self.error(key, problem)
        if choices is not None and value not in choices:
            raise self.error(key, f"expected one of {list(choices)}, got {value!r}")
        return value

    def name(self, key: str, default: Any = None) -> str:
        """A name printed back to the user (a robot's, a body's): :meth:`text` of at most
        MAX_NAME_CHARS characters."""
        return self.text(key, default, max_chars=MAX_NAME_CHARS)

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

    def mark_read(self, *keys: str) -> None:
        """Count ``keys`` as read (another reader validates them)."""
        self._seen.update(keys)

    def done(self) -> None:
        """Reject keys nobody read: a typo must not be silently ignored."""
        unknown = sorted(set(self.data) - self._seen)
        if unknown:
            known = ", ".join(sorted(self._seen)) or "none"
            raise self.error(shown_key(unknown[0]), f"unknown key (known keys here: {known})")


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 200 else f"{text[:200]}... ({len(text)} chars)"


_REQUIRED = object()
