"""Which serial ports snakebot opens: device paths, and the emulator's URLs.

A port string goes to pyserial, whose ``serial_for_url`` opens any URL scheme it knows:
``socket://host:port`` makes a TCP connection, ``spy://PORT?file=PATH`` truncates ``PATH`` for a
traffic dump, ``hwgrep://`` opens whichever port matches a pattern. None of that may come from a
robot file that was copied from someone else, and none of it is needed to drive servos. The rule,
enforced here and called by every port opener (``ServoBus``, hence the backend and the setup
tools' ``Link``) and by the robot-file loader:

- a device path (``/dev/ttyUSB0``, ``/dev/pts/3``, ``COM3``) anywhere;
- a ``dxlemu://NAME[?...]`` URL (the in-process emulator, snakebot.emulation.urlhandler) only
  where it cannot come from a file: the command line's ``--port`` or a program's own argument;
- nothing else.
"""

from __future__ import annotations

from pathlib import Path

from snakebot.errors import ConfigError

EMULATOR_SCHEME = "dxlemu"
"""The URL scheme of the in-process emulator; snakebot.emulation.registry takes it from here."""

DEVICE_EXAMPLES = "a serial device such as /dev/ttyUSB0, /dev/tty.usbserial-XXXX or COM3"


def url_scheme(port: str) -> str | None:
    """The URL scheme of ``port`` in lower case (pyserial's reading), or None for a device path."""
    if "://" not in port:
        return None
    return port.split("://", 1)[0].strip().lower()


def check_port(
    port: str, *, source: str | Path = "port", key: str = "", allow_emulator: bool = True
) -> str:
    """``port`` if snakebot may open it, else ConfigError naming ``source`` and ``key``.

    ``allow_emulator`` admits ``dxlemu://`` URLs (never set it for a value read from a file).
    """
    if not isinstance(port, str) or not port.strip():
        raise ConfigError(source, key, f"expected {DEVICE_EXAMPLES}, got {port!r}")
    if any(ord(ch) < 0x20 or ord(ch) == 0x7F for ch in port):
        raise ConfigError(source, key, f"a port name has no control characters, got {port!r}")
    scheme = url_scheme(port)
    if scheme is None or (scheme == EMULATOR_SCHEME and allow_emulator):
        return port
    if scheme == EMULATOR_SCHEME:
        raise ConfigError(
            source,
            key,
            f"refusing {port!r} here: emulator URLs ({EMULATOR_SCHEME}://) work only "
            f"as a port given directly (the command line's, a program's), never from a file; this "
            f"needs {DEVICE_EXAMPLES}",
        )
    also = f", or an emulator URL {EMULATOR_SCHEME}://NAME" if allow_emulator else ""
    raise ConfigError(
        source,
        key,
        f"refusing to open {port!r}: a {scheme}:// URL is not a serial port; "
        f"snakebot opens {DEVICE_EXAMPLES}{also}",
    )
