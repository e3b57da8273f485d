"""A terrain key's bounds and unit, and parsing one ``key=value`` against them."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from snakebot.errors import ConfigError


@dataclass(frozen=True)
class Param:
    """One ``--terrain`` key: accepted range (inclusive) or choices, unit and meaning."""

    low: float = 0.0
    high: float = 0.0
    unit: str = ""
    help: str = ""
    integer: bool = False
    choices: tuple[str, ...] = ()

    def accepted(self) -> str:
        """The accepted values in words, e.g. ``0..45 deg`` or ``row|field``."""
        if self.choices:
            return "|".join(self.choices)
        unit = f" {self.unit}" if self.unit else ""
        if self.integer:
            return f"an integer {int(self.low)}..{int(self.high)}{unit}"
        return f"{self.low:g}..{self.high:g}{unit}"

    def parse(self, option: str, key: str, raw: str) -> float | int | str:
        """The value of ``raw``; ConfigError naming ``key`` and the accepted range otherwise."""
        text = raw.strip()
        if self.choices:
            if text not in self.choices:
                raise ConfigError(option, key, f"expected {self.accepted()}, got {raw!r}")
            return text
        try:
            value = float(text)
        except ValueError:
            raise ConfigError(option, key, f"expected {self.accepted()}, got {raw!r}") from None
        if self.integer:
            if not value.is_integer():
                raise ConfigError(option, key, f"expected {self.accepted()}, got {raw!r}")
            value = int(value)
        self.check(option, key, value)
        return value

    def check(self, option: str, key: str, value: Any) -> None:
        """ConfigError unless ``value`` is inside the accepted range or choices."""
        if self.choices:
            if value not in self.choices:
                raise ConfigError(option, key, f"expected {self.accepted()}, got {value!r}")
            return
        if not (isinstance(value, int | float) and math.isfinite(value)):
            raise ConfigError(option, key, f"expected {self.accepted()}, got {value!r}")
        if not self.low <= value <= self.high:
            raise ConfigError(option, key, f"expected {self.accepted()}, got {value:g}")


def param(
    default: Any,
    low: float = 0.0,
    high: float = 0.0,
    unit: str = "",
    help: str = "",
    *,
    integer: bool = False,
    choices: tuple[str, ...] = (),
) -> Any:
    """A dataclass field with ``default`` and a :class:`Param` in its metadata."""
    spec = Param(low, high, unit, help, integer, choices)
    return field(default=default, metadata={"param": spec})
