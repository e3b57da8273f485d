"""Where driving input comes from: one interface for scripts, the terminal and gamepads.

Every source is polled once a control cycle and never blocks. Time is drive time: robot seconds
since the drive started (simulated on the twin, the wall clock on hardware). A source that loses
its device (terminal closed, gamepad unplugged) sets ``lost`` and the drive stops safely.
"""

from __future__ import annotations

import abc
import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import TextIO

from snakebot.drive.keymap import action_for
from snakebot.drive.keys import normalise
from snakebot.errors import ConfigError, SnakebotError


class DriveInputError(SnakebotError):
    """The driving input was lost (terminal closed, gamepad unplugged); the snake was stopped."""


class InputDeviceError(SnakebotError):
    """The input device asked for is not there (no gamepad connected): connecting it fixes it,
    the command line was right."""


@dataclass(frozen=True)
class InputEvent:
    """One key at drive time ``time_s`` (s since the drive started)."""

    time_s: float
    key: str


class InputSource(abc.ABC):
    """Keys for the drive, polled every cycle. Use as a context manager (``open``/``close``).

    ``lost`` is a reason once the device is gone; ``exhausted`` is true when no key can come
    any more (the end of a script); ``live`` is false for a script.
    """

    name: str = "input"
    lost: str | None = None
    live: bool = True
    """True when a person makes the keys as they go (terminal, gamepad): a burst of them is a
    mistake (a paste) the drive drops (snakebot.drive.gate); a script's keys are all meant."""

    @property
    def exhausted(self) -> bool:
        """True when the source will produce no more keys (scripts)."""
        return False

    def open(self) -> None:
        """Acquire the device (raw mode, joystick); default: nothing to do."""
        return None

    def close(self) -> None:
        """Release the device and restore what open() changed; idempotent."""
        return None

    @abc.abstractmethod
    def poll(self, now_s: float) -> list[str]:
        """Keys that arrived by drive time ``now_s``; never blocks."""

    def __enter__(self) -> InputSource:
        self.open()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


class ScriptSource(InputSource):
    """Keys from a script: ``<time_s> <key>`` lines, ``#`` comments, times not decreasing."""

    def __init__(self, events: Iterable[InputEvent], name: str = "script") -> None:
        self.events = tuple(events)
        self.name = name
        self.live = False
        self._next = 0

    @classmethod
    def load(cls, path: str | Path) -> ScriptSource:
        """Parse a script file; ConfigError naming ``file:line`` and what was expected."""
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise ConfigError(path, "", f"cannot read the drive script ({exc.strerror})") from exc
        except UnicodeDecodeError as exc:
            raise ConfigError(
                path,
                "",
                f"not UTF-8 text (byte {exc.start}: {exc.reason}); a drive script is "
                "'<time_s> <key>' lines",
            ) from None
        return cls(parse_script(text, str(path)), f"script {path}")

    @property
    def exhausted(self) -> bool:
        """True once every line has been played."""
        return self._next >= len(self.events)

    def poll(self, now_s: float) -> list[str]:
        """The keys whose time has come (within a microsecond: float sums of periods)."""
        keys = []
        while self._next < len(self.events) and self.events[self._next].time_s <= now_s + 1e-6:
            keys.append(self.events[self._next].key)
            self._next += 1
        return keys


def parse_script(text: str, source: str = "<script>") -> list[InputEvent]:
    """Events of a script's text; ConfigError("<source>:<line>") for a bad line."""
    events: list[InputEvent] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split(" #", 1)[0].split("\t#", 1)[0].strip()
        if not line or line.startswith("#"):
            continue
        where = f"{source}:{number}"
        fields = line.split()
        if len(fields) != 2:
            raise ConfigError(
                where, "", f"expected '<time_s> <key>' (e.g. '1.5 w'), got {raw.strip()!r}"
            )
        try:
            time_s = float(fields[0])
        except ValueError:
            time_s = math.nan
        if not (math.isfinite(time_s) and time_s >= 0.0):
            raise ConfigError(
                where, "", f"expected a time in seconds >= 0 first, got {fields[0]!r}"
            )
        if events and time_s < events[-1].time_s:
            raise ConfigError(
                where,
                "",
                f"time {time_s:g} s is before the line above ({events[-1].time_s:g} "
                "s); keep the lines in time order",
            )
        try:
            key = normalise(fields[1])
        except ValueError as exc:
            raise ConfigError(where, "", str(exc)) from None
        if action_for(key) is None:
            raise ConfigError(
                where,
                "",
                f"key {key!r} does nothing while driving (see the key map in docs/driving.md)",
            )
        events.append(InputEvent(time_s, key))
    return events


class ScriptRecorder:
    """Writes the keys a drive applied as a script that replays it (``--record``)."""

    def __init__(self, stream: TextIO, header: str = "") -> None:
        self.stream = stream
        if header:
            for line in header.splitlines():
                stream.write(f"# {line}\n")
        stream.flush()

    def __call__(self, event: InputEvent) -> None:
        """Append one applied key."""
        self.stream.write(f"{event.time_s:.6f} {event.key}\n")
        self.stream.flush()
