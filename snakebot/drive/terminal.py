"""Keys from the terminal: raw mode on the controlling terminal, read without blocking.

Raw mode (no echo, no line buffering, no signal keys) so every key arrives at once and Ctrl-C,
Ctrl-Z and Ctrl-\\ are keys the drive handles (stop), not signals that would suspend or kill the
control loop. Output processing stays on, so the display's newlines still work. The previous
settings come back on close, whatever happened. A terminal that goes away (EOF, EIO) sets
``lost``; :func:`hung_up` and :func:`discard_output` let a command finish quietly on an
output terminal that went away with it.
"""

from __future__ import annotations

import contextlib
import errno
import io
import os
import select
import sys
from typing import IO, Any

from snakebot.drive.keys import KeyDecoder
from snakebot.drive.sources import InputSource
from snakebot.errors import ConfigError

TermAttrs = list[Any]

GONE_ERRNOS = frozenset({errno.EIO, errno.ENXIO, errno.EPIPE})
"""What writing to an output that went away raises: a closed terminal (a hung-up pty, a
vanished device), a pipe whose reader quit."""

READ_BYTES = 512
"""Bytes read from the terminal in one cycle at most: the decoder's time stays bounded (a
paste drains over a few cycles; snakebot.drive.gate drops it)."""


class TerminalSource(InputSource):
    """Keys typed on ``fd`` (default: standard input if it is a terminal, else /dev/tty).

    Raises ConfigError on open when there is no terminal to read.
    """

    def __init__(self, fd: int | None = None) -> None:
        self.name = "terminal"
        self._fd = fd
        self._owned = False
        self._saved: TermAttrs | None = None
        self._decoder = KeyDecoder()

    @property
    def fd(self) -> int | None:
        """The terminal's file descriptor while open."""
        return self._fd

    def open(self) -> None:
        """Find the terminal and put it in raw mode (output processing kept)."""
        try:
            import termios
        except ImportError:  # Windows: no termios
            raise ConfigError(
                "script",
                "",
                "keyboard driving needs a POSIX terminal (Linux, macOS); "
                "here, drive with a gamepad or a key script",
            ) from None

        if self._fd is None:
            if sys.stdin is not None and sys.stdin.isatty():
                self._fd = sys.stdin.fileno()
            else:
                try:
                    self._fd = os.open("/dev/tty", os.O_RDWR | os.O_NOCTTY)
                except OSError:
                    raise ConfigError(
                        "script",
                        "",
                        "no terminal to read keys from: drive from a terminal, or "
                        "give a key script or a gamepad",
                    ) from None
                self._owned = True
        if not os.isatty(self._fd):
            raise ConfigError("script", "", "standard input is not a terminal: give a key script")
        self.name = f"terminal {os.ttyname(self._fd)}"
        self._saved = termios.tcgetattr(self._fd)
        mode = termios.tcgetattr(self._fd)
        mode[0] &= ~(  # iflag: no break signal, no CR->NL, no parity strip, no XON/XOFF
            termios.BRKINT | termios.ICRNL | termios.INPCK | termios.ISTRIP | termios.IXON
        )
        mode[3] &= ~(termios.ECHO | termios.ICANON | termios.IEXTEN | termios.ISIG)  # lflag
        mode[6][termios.VMIN] = 1
        mode[6][termios.VTIME] = 0
        termios.tcsetattr(self._fd, termios.TCSANOW, mode)

    def poll(self, now_s: float) -> list[str]:
        """Keys typed since the last poll (from READ_BYTES at most); sets ``lost`` if the
        terminal is gone."""
        if self._fd is None or self.lost is not None:
            return []
        try:
            ready, _, _ = select.select([self._fd], [], [], 0.0)
            data = os.read(self._fd, READ_BYTES) if ready else b""
        except OSError as exc:
            if exc.errno in (errno.EAGAIN, errno.EINTR):
                return []
            self.lost = f"the terminal closed ({os.strerror(exc.errno or 0)})"
            return []
        if ready and not data:
            self.lost = "the terminal closed (end of input)"
            return []
        if not data:
            return self._decoder.flush()  # a lone ESC with nothing after it this cycle
        return self._decoder.feed(data)

    def close(self) -> None:
        """Restore the terminal's settings; close it if we opened it. Idempotent."""
        fd, saved = self._fd, self._saved
        self._saved = None
        if fd is not None and saved is not None:
            import termios

            with contextlib.suppress(OSError, termios.error):  # gone: nothing to restore
                termios.tcsetattr(fd, termios.TCSANOW, saved)
        if fd is not None and self._owned:
            self._owned = False
            os.close(fd)
            self._fd = None


def hung_up(stream: IO[Any]) -> bool:
    """True when ``stream``'s file is a terminal that hung up (its window was closed)."""
    try:
        poller = select.poll()
        poller.register(stream.fileno(), select.POLLOUT)
        events = poller.poll(0)
    except (OSError, ValueError, AttributeError, io.UnsupportedOperation):
        return False
    return any(event & (select.POLLHUP | select.POLLERR) for _, event in events)


def discard_output(stream: IO[Any]) -> None:
    """Point ``stream``'s file descriptor at /dev/null: what it still buffers for a terminal
    that is gone is dropped instead of failing again when Python flushes it at exit."""
    with contextlib.suppress(OSError, ValueError, AttributeError, io.UnsupportedOperation):
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, stream.fileno())
        finally:
            os.close(devnull)
