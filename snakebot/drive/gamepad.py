"""Keys from a gamepad, through pygame-ce's joystick module (SDL2) with no window.

The left stick sets speed (up = forward) and turn (left = left) directly as ``speed=V`` /
``turn=V`` keys, so a gamepad drive records and replays like a keyboard one. Buttons use SDL's
numbering, the same for Xbox-style pads on Linux, Windows and macOS: A (0) pause/resume, B (1)
halt, X (2) next gait, Y (3) stop. The d-pad moves amplitude (up/down) and wavelength
(right/left). A stick held off centre when the drive starts is ignored until it has been
centred once, so a pad lying on its stick cannot start the snake. Unplugging the pad sets
``lost``: the drive stops safely.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from snakebot.drive.sources import InputDeviceError, InputSource
from snakebot.errors import MissingDependencyError

INSTALL = "pip install 'snakebot[gamepad]'"
DEAD_ZONE = 0.15
"""Stick travel (of 1) read as centred: worn sticks rest a little off centre."""
RESOLUTION = 0.05
"""Stick values are rounded to this, so a still hand sends no stream of tiny changes."""
SPEED_AXIS, TURN_AXIS = 1, 0
BUTTONS = {0: "space", 1: "x", 2: "tab", 3: "q"}
HAT = {(0, 1): "+", (0, -1): "-", (1, 0): "]", (-1, 0): "["}


def stick_value(raw: float) -> float:
    """A stick axis (-1..1, +1 down/right) as a control value: dead zone, rescaled, rounded."""
    magnitude = abs(raw)
    if magnitude <= DEAD_ZONE:
        return 0.0
    scaled = min((magnitude - DEAD_ZONE) / (1.0 - DEAD_ZONE), 1.0)
    value = round(scaled / RESOLUTION) * RESOLUTION
    return value if raw > 0 else -value


@dataclass
class PadMapper:
    """Turns joystick events into key names, remembering the last stick values sent."""

    instance_id: int
    sent: dict[str, float] = field(default_factory=lambda: {"speed": 0.0, "turn": 0.0})
    armed: dict[str, bool] = field(default_factory=lambda: {"speed": True, "turn": True})
    unplugged: bool = False

    def prime(self, axis: int, raw: float) -> None:
        """The stick's position when the drive starts: off centre, it waits to be centred."""
        control = "speed" if axis == SPEED_AXIS else "turn"
        self.armed[control] = stick_value(raw) == 0.0

    def keys(self, events: Iterable[tuple[str, dict[str, Any]]]) -> list[str]:
        """Keys for (kind, attributes) events: kind is axis, button, hat or removed."""
        out: list[str] = []
        for kind, attrs in events:
            if attrs.get("instance_id") != self.instance_id:
                continue
            if kind == "removed":
                self.unplugged = True
            elif kind == "axis" and attrs["axis"] in (SPEED_AXIS, TURN_AXIS):
                control = "speed" if attrs["axis"] == SPEED_AXIS else "turn"
                # up and left are negative on a pad; + 0.0 turns -0.0 into 0.0
                value = -stick_value(float(attrs["value"])) + 0.0
                if not self.armed[control]:
                    self.armed[control] = value == 0.0
                elif value != self.sent[control]:
                    self.sent[control] = value
                    out.append(f"{control}={value:g}")
            elif kind == "button" and attrs["button"] in BUTTONS:
                out.append(BUTTONS[attrs["button"]])
            elif kind == "hat" and tuple(attrs["value"]) in HAT:
                out.append(HAT[tuple(attrs["value"])])
        return out


class GamepadSource(InputSource):
    """Keys from gamepad ``index`` (0: the first one connected). Raises MissingDependencyError
    without pygame-ce, InputDeviceError when no gamepad is connected."""

    def __init__(self, index: int = 0) -> None:
        self.name = "gamepad"
        self.index = index
        self._pygame: Any = None
        self._mapper: PadMapper | None = None

    def open(self) -> None:
        """Start SDL's joystick subsystem (no window, no sound) and open the pad."""
        os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
        os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        # Read the pad even while the terminal, not an SDL window, has the focus.
        os.environ.setdefault("SDL_JOYSTICK_ALLOW_BACKGROUND_EVENTS", "1")
        try:
            import pygame
        except ImportError as exc:
            raise MissingDependencyError(f"gamepad driving needs pygame-ce: {INSTALL}") from exc
        pygame.display.init()  # the event queue lives in SDL's video subsystem
        pygame.joystick.init()
        self._pygame = pygame
        if pygame.joystick.get_count() <= self.index:
            self.close()
            raise InputDeviceError(
                "gamepad: no gamepad found: plug one in (or drive from the keyboard)"
            )
        pad = pygame.joystick.Joystick(self.index)
        self.name = f"gamepad {pad.get_name()!r}"
        self._pad = pad
        self._mapper = PadMapper(pad.get_instance_id())
        pygame.event.clear()
        for axis in (SPEED_AXIS, TURN_AXIS):
            if axis < pad.get_numaxes():
                self._mapper.prime(axis, pad.get_axis(axis))

    def poll(self, now_s: float) -> list[str]:
        """Keys from the events queued since the last poll; sets ``lost`` on unplug."""
        if self._pygame is None or self._mapper is None or self.lost is not None:
            return []
        pygame = self._pygame
        kinds = {
            pygame.JOYAXISMOTION: "axis",
            pygame.JOYBUTTONDOWN: "button",
            pygame.JOYHATMOTION: "hat",
            pygame.JOYDEVICEREMOVED: "removed",
        }
        events = [
            (kinds[event.type], event.dict) for event in pygame.event.get() if event.type in kinds
        ]
        keys = self._mapper.keys(events)
        if self._mapper.unplugged:
            self.lost = f"{self.name} was unplugged"
        return keys

    def close(self) -> None:
        """Shut SDL's joystick and video subsystems down; idempotent."""
        pygame, self._pygame = self._pygame, None
        if pygame is not None:
            pygame.joystick.quit()
            pygame.display.quit()
