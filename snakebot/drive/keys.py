"""Key names shared by the terminal, the gamepad and scripts, and the terminal's byte decoder.

A key is a printable character (``w``, ``1``, ``+``), a named key (``up``, ``space``,
``ctrl-c``) or an analog set point from a stick, ``speed=0.5`` / ``turn=-1`` (-1..1 of the
control's range). Scripts and recordings use the same names, so a recorded drive replays exactly.
"""

from __future__ import annotations

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
    """Turns the bytes a terminal sends into key names; keeps a sequence split across reads.

    A lone ESC is reported as ``esc`` only when the next read does not continue it.
    """

    def __init__(self) -> None:
        self._pending = ""

    def feed(self, data: bytes) -> list[str]:
        """Key names for ``data``; undecodable bytes and unknown sequences are dropped."""
        text = self._pending + data.decode("utf-8", errors="ignore")
        self._pending = ""
        keys: list[str] = []
        i = 0
        while i < len(text):
            char = text[i]
            if char == "\x1b":
                rest = text[i : i + 3]
                if len(rest) < 3 and rest in ("\x1b", "\x1b[", "\x1bO"):
                    self._pending = rest  # maybe the start of a sequence: wait for more
                    break
                name = _SEQUENCES.get(rest)
                if name is not None:
                    keys.append(name)
                    i += 3
                    continue
                i += _skip_sequence(text, i)
                if i - 1 >= 0 and text[i - 1] == "\x1b":
                    keys.append("esc")
                continue
            name = _BYTE_NAMES.get(char)
            if name is not None:
                keys.append(name)
            elif char.isprintable():
                keys.append(char)
            i += 1
        return keys

    def flush(self) -> list[str]:
        """Keys held back waiting for a sequence's next byte (a lone ESC)."""
        pending, self._pending = self._pending, ""
        return ["esc"] if pending == "\x1b" else []


def _skip_sequence(text: str, start: int) -> int:
    """Length of the escape sequence at ``start`` (1 for a lone ESC)."""
    if text[start + 1 : start + 2] not in ("[", "O"):
        return 1
    end = start + 2
    while end < len(text) and not ("@" <= text[end] <= "~"):
        end += 1
    return end + 1 - start
