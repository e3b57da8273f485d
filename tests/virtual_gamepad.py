"""A gamepad plugged in through SDL's own virtual-joystick API, for tests without hardware.

pygame-ce bundles SDL2; its ``SDL_JoystickAttachVirtual`` adds a pad that the real joystick and
event code sees like a USB one (axes, buttons, hot-plug and unplug events). ``ctypes`` reaches
the library pygame already loaded, so both share SDL's state.
"""

from __future__ import annotations

import ctypes
import glob
import os
import sys
from types import ModuleType

SDL_JOYSTICK_TYPE_GAMECONTROLLER = 1


def _sdl(pygame: ModuleType) -> ctypes.CDLL:
    root = os.path.dirname(os.path.dirname(pygame.__file__))
    found = sorted(glob.glob(os.path.join(root, "pygame_ce.libs", "libSDL2-2*")))
    if not found or not sys.platform.startswith("linux"):
        raise RuntimeError("the SDL2 library bundled with pygame-ce (Linux wheels) is needed")
    lib = ctypes.CDLL(found[0])
    lib.SDL_JoystickAttachVirtual.restype = ctypes.c_int
    lib.SDL_JoystickOpen.restype = ctypes.c_void_p
    lib.SDL_JoystickSetVirtualAxis.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int16]
    lib.SDL_JoystickSetVirtualButton.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_uint8]
    lib.SDL_JoystickSetVirtualHat.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_uint8]
    lib.SDL_JoystickClose.argtypes = [ctypes.c_void_p]
    return lib


class VirtualPad:
    """An Xbox-style pad: 6 axes, 11 buttons, one hat. SDL must already be initialised."""

    def __init__(self, pygame: ModuleType) -> None:
        self._sdl = _sdl(pygame)
        self.index = self._sdl.SDL_JoystickAttachVirtual(SDL_JOYSTICK_TYPE_GAMECONTROLLER, 6, 11, 1)
        if self.index < 0:
            raise RuntimeError("SDL refused to attach a virtual joystick")
        self._handle = self._sdl.SDL_JoystickOpen(self.index)
        self.attached = True

    def axis(self, axis: int, value: float) -> None:
        """Move an axis to value in -1..1 (+1 is down/right on a stick)."""
        raw = max(-32768, min(32767, round(value * 32767)))
        self._sdl.SDL_JoystickSetVirtualAxis(self._handle, axis, raw)
        self._sdl.SDL_JoystickUpdate()

    def press(self, button: int) -> None:
        """Press and release a button."""
        for state in (1, 0):
            self._sdl.SDL_JoystickSetVirtualButton(self._handle, button, state)
            self._sdl.SDL_JoystickUpdate()

    def unplug(self) -> None:
        """Detach the pad, as pulling its cable does."""
        if self.attached:
            self.attached = False
            self._sdl.SDL_JoystickClose(self._handle)
            self._sdl.SDL_JoystickDetachVirtual(self.index)
            self._sdl.SDL_JoystickUpdate()
