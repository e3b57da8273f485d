"""What each key does while driving: the default key map and the actions it produces."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from snakebot.drive.keys import analog

Control = Literal["speed", "turn", "amplitude", "wavelength"]

SPEED_STEP = 0.25
"""One press of faster/slower: a quarter of the gait's own frequency."""
TURN_STEP = 0.25
"""One press of left/right: a quarter of the steering range."""
SHAPE_STEP = 0.1
"""One press of the amplitude or wavelength keys: a tenth of the configured value."""


@dataclass(frozen=True)
class Nudge:
    """Move one control's set point by ``step`` (it is clipped to the gait's bounds)."""

    control: Control
    step: float


@dataclass(frozen=True)
class SetAnalog:
    """Set speed or turn to ``value`` (-1..1) of its range, from a stick or a script."""

    control: Literal["speed", "turn"]
    value: float


@dataclass(frozen=True)
class Halt:
    """Speed and turn to zero: the gait freezes in its current shape."""


@dataclass(frozen=True)
class SelectGait:
    """Switch to gait number ``index`` (0-based) of the drive's gait list."""

    index: int


@dataclass(frozen=True)
class CycleGait:
    """Switch to the next (+1) or previous (-1) gait of the list."""

    step: int


@dataclass(frozen=True)
class TogglePause:
    """Pause to the rest pose, or resume the gait."""


@dataclass(frozen=True)
class Quit:
    """Stop: blend to the rest pose, then leave the servos as the stop policy says."""


Action = Nudge | SetAnalog | Halt | SelectGait | CycleGait | TogglePause | Quit

DEFAULT_KEYS: dict[str, Action] = {
    "w": Nudge("speed", SPEED_STEP),
    "up": Nudge("speed", SPEED_STEP),
    "s": Nudge("speed", -SPEED_STEP),
    "down": Nudge("speed", -SPEED_STEP),
    "a": Nudge("turn", TURN_STEP),
    "left": Nudge("turn", TURN_STEP),
    "d": Nudge("turn", -TURN_STEP),
    "right": Nudge("turn", -TURN_STEP),
    "x": Halt(),
    "+": Nudge("amplitude", SHAPE_STEP),
    "=": Nudge("amplitude", SHAPE_STEP),
    "-": Nudge("amplitude", -SHAPE_STEP),
    "]": Nudge("wavelength", SHAPE_STEP),
    "[": Nudge("wavelength", -SHAPE_STEP),
    "tab": CycleGait(1),
    "space": TogglePause(),
    "q": Quit(),
    "esc": Quit(),
    "ctrl-c": Quit(),
    "ctrl-d": Quit(),
    **{str(n): SelectGait(n - 1) for n in range(1, 10)},
}
"""Keys to actions; letters match either case."""

HELP = (
    ("w / up", "faster (below 0: backwards)", "w/s speed"),
    ("s / down", "slower", ""),
    ("a / left", "turn left", "a/d turn"),
    ("d / right", "turn right", ""),
    ("x", "halt: speed and turn to 0", "x halt"),
    ("+ / -", "amplitude up / down", "+/- amplitude"),
    ("] / [", "longer / shorter wave", "]/[ wave"),
    ("1-9, tab", "gait number n, next gait", "1-9 tab gait"),
    ("space", "pause to the rest pose / resume", "space pause"),
    ("q, esc, ctrl-c", "stop (rest pose, then the stop policy)", "q stop"),
)
"""The key map as (keys, what they do, short form for the display) rows."""


def action_for(key: str, keys: dict[str, Action] | None = None) -> Action | None:
    """The action of ``key`` (a normalised key name), None when the key does nothing."""
    value = analog(key)
    if value is not None:
        return SetAnalog("speed" if value[0] == "speed" else "turn", value[1])
    table = DEFAULT_KEYS if keys is None else keys
    action = table.get(key)
    if action is None and len(key) == 1:
        action = table.get(key.lower())
    return action
