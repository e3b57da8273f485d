"""Keys to a live gait: set points, gait switches, pause and stop; the one place input acts."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

from snakebot.drive.keymap import (
    DEFAULT_KEYS,
    Action,
    CycleGait,
    Halt,
    Nudge,
    Quit,
    SelectGait,
    SetAnalog,
    TogglePause,
    action_for,
)
from snakebot.drive.sources import InputEvent
from snakebot.errors import GaitError
from snakebot.gaits.live import LiveGait


@dataclass(frozen=True)
class GaitChoice:
    """One gait of the drive's list: its name and the parameters over its defaults."""

    name: str
    params: Mapping[str, object] = field(default_factory=dict)


class DriveController:
    """Applies keys to ``live``; ``gaits`` are what the number keys select (1 is the first).

    ``on_event`` sees every key that did something, with its drive time (``--record``).
    ``stop_reason`` is set by a quit key, the end of a script, lost input or a signal; the
    live gait is then stopping toward the rest pose. ``notice`` is the last message for the
    display (a refused gait, say).
    """

    def __init__(
        self,
        live: LiveGait,
        gaits: Sequence[GaitChoice],
        *,
        keys: Mapping[str, Action] | None = None,
        on_event: Callable[[InputEvent], None] | None = None,
    ) -> None:
        if not gaits:
            raise GaitError("drive: expected at least one gait to drive")
        self.live = live
        self.gaits = tuple(gaits)
        self.keys = dict(DEFAULT_KEYS if keys is None else keys)
        self.on_event = on_event
        self.stop_reason: str | None = None
        self.notice = ""
        self.events = 0
        self._index = 0

    @property
    def gait_index(self) -> int:
        """Index of the gait driven (or resumed after a pause) in ``gaits``."""
        return self._index

    def begin(self) -> None:
        """Start on the first gait, standing still (speed 0)."""
        self._select(0)

    def apply(self, key: str, now_s: float) -> bool:
        """Do what ``key`` means at drive time ``now_s``; False when it does nothing."""
        action = action_for(key, self.keys)
        if action is None or self.stop_reason is not None:
            return False
        self._act(action)
        self.events += 1
        if self.on_event is not None:
            self.on_event(InputEvent(now_s, key))
        return True

    def settles(self, key: str) -> bool:
        """True for a key that only stops or halts the snake (never dropped from a flood)."""
        return isinstance(action_for(key, self.keys), Quit | Halt)

    def request_stop(self, reason: str) -> None:
        """Stop driving: blend to the rest pose; the first reason given is kept."""
        if self.stop_reason is None:
            self.stop_reason = reason
            self.live.stop()

    def _act(self, action: Action) -> None:
        setpoint = self.live.setpoint
        if isinstance(action, Nudge):
            value = getattr(setpoint, action.control) + action.step
            self.live.set_controls(replace(setpoint, **{action.control: round(value, 9)}))
        elif isinstance(action, SetAnalog):
            value = action.value
            if action.control == "speed":
                value *= self.live.status().speed_limit
            self.live.set_controls(replace(setpoint, **{action.control: value}))
        elif isinstance(action, Halt):
            self.live.set_controls(replace(setpoint, speed=0.0, turn=0.0))
        elif isinstance(action, SelectGait | CycleGait):
            index = (
                action.index
                if isinstance(action, SelectGait)
                else (self._index + action.step) % len(self.gaits)
            )
            if index < len(self.gaits):
                self._select(index)
            else:
                self.notice = f"no gait {index + 1}: the list has {len(self.gaits)}"
        elif isinstance(action, TogglePause):
            if self.live.status().mode == "paused":
                self.live.resume()
            else:
                self.live.pause()
        elif isinstance(action, Quit):
            self.request_stop("quit")

    def _select(self, index: int) -> None:
        choice = self.gaits[index]
        self.live.select(choice.name, choice.params)
        self._index = index
        self.notice = ""
