"""Key names shared by the terminal, the gamepad and scripts, and the terminal's byte decoder.

A key is a printable character (``w``, ``1``, ``+``), a named key (``up``, ``space``,
``ctrl-c``) or an analog set point from a stick, ``speed=0.5`` / ``turn=-1`` (-1..1 of the
control's range). Scripts and recordings use the same names, so a recorded drive replays exactly.
"""

from __future__ import annotations

import codecs
import math
import re

NAMED = {
    "up": "\x1b[A",
    "down": "\x1b[B",
    "right": "\x1b[C",
    "left": "\x1b[D",
    "space": " ",
    "enter": "\r",
    "tab": "\t",
    "backspace": "\x7f",
    "esc": "\x1b",
}
"""Named keys and the bytes a terminal sends for them (arrows in normal cursor mode)."""
CONTROL = {f"ctrl-{chr(c)}": chr(c - 96) for c in range(ord("a"), ord("z") + 1)}
ANALOG = ("speed", "turn")
"""Analog controls a key can set directly: ``speed=VALUE`` / ``turn=VALUE``, VALUE in -1..1."""
_ANALOG = re.compile(r"^(speed|turn)=(.+)$")
_SEQUENCES = {
    **{seq: name for name, seq in NAMED.items() if seq.startswith("\x1b[")},
    **{"\x1bO" + seq[-1]: name for name, seq in NAMED.items() if seq.startswith("\x1b[")},
}
"""Escape sequences to key names: CSI arrows and the SS3 form of application cursor mode."""
_BYTE_NAMES = {
    **{seq: name for name, seq in NAMED.items() if len(seq) == 1},
    "\n": "enter",
    "\x08": "backspace",
    **{seq: name for name, seq in CONTROL.items() if seq not in "\t\r\n\x08"},
}


def normalise(key: str) -> str:
    """The canonical name of ``key`` (case of named keys folded, ``speed=+0.50`` as
    ``speed=0.5``). Raises ValueError saying what a key looks like."""
    text = key.strip()
    lowered = text.lower()
    if lowered in NAMED or lowered in CONTROL:
        return lowered
    if len(text) == 1 and text.isprintable():
        return text
    match = _ANALOG.match(lowered)
    if match:
        try:
            value = float(match.group(2))
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and -1.0 <= value <= 1.0):
            raise ValueError(f"{match.group(1)}= needs a number in -1..1, got {match.group(2)!r}")
        return f"{match.group(1)}={value:g}"
    raise ValueError(
        f"unknown key {key!r}: expected one character (w, 1, +), a named key "
        f"({', '.join(NAMED)}, ctrl-a..ctrl-z) or speed=V / turn=V with V in -1..1"
    )


def analog(key: str) -> tuple[str, float] | None:
    """("speed" or "turn", value) for an analog key, None for any other."""
    name, sep, value = key.partition("=")
    return (name, float(value)) if sep and name in ANALOG else None


class KeyDecoder:
    """Turns the bytes a terminal sends into key names, one byte at a time, so a key split
    across reads (``ESC [ 1 ;`` then ``5 A``) decodes as if it came whole.

    A lone ESC is reported as ``esc`` only when the next read does not continue it. Escape
    sequences that are not keys of the drive are dropped whole; a control byte inside one
    ends it and counts as itself (ctrl-c in line noise still stops), as a VT parser does.
    Any bytes are accepted: invalid UTF-8 is dropped, nothing raises.
    """

    def __init__(self) -> None:
        self._utf8 = codecs.getincrementaldecoder("utf-8")(errors="ignore")
        self._state = _GROUND
        self._sequence = ""  # the escape sequence so far, while in _CSI / _SS3

    def feed(self, data: bytes) -> list[str]:
        """Key names for ``data``; undecodable bytes and unknown sequences are dropped."""
        keys: list[str] = []
        for char in self._utf8.decode(data):
            self._step(char, keys)
        return keys

    def flush(self) -> list[str]:
        """Keys held back waiting for a sequence's next byte (a lone ESC); a sequence cut
        short is dropped."""
        self._utf8.reset()
        state, self._state, self._sequence = self._state, _GROUND, ""
        return ["esc"] if state == _ESC else []

    def _step(self, char: str, keys: list[str]) -> None:
        state = self._state
        if state == _ESC:
            if char in "[O":
                self._state, self._sequence = (_CSI if char == "[" else _SS3), "\x1b" + char
                return
            keys.append("esc")  # ESC then something else: the ESC key, then that
            self._state = _GROUND
        elif state in (_CSI, _SS3):
            if " " <= char <= "?":  # parameter and intermediate bytes
                if len(self._sequence) <= _LONGEST_SEQUENCE:
                    self._sequence += char
                return
            self._state = _GROUND
            if "@" <= char <= "~":  # the final byte: the sequence is complete
                name = _SEQUENCES.get(self._sequence + char)
                if name is not None:
                    keys.append(name)
                return
            # anything else cuts the sequence short and counts as itself
        if char == "\x1b":
            self._state = _ESC
            return
        name = _BYTE_NAMES.get(char)
        if name is not None:
            keys.append(name)
        elif char.isprintable():
            keys.append(char)


_GROUND, _ESC, _CSI, _SS3 = range(4)
_LONGEST_SEQUENCE = max(len(seq) for seq in _SEQUENCES)
"""Longer sequences cannot be keys: only this much of one is kept (memory stays bounded)."""
