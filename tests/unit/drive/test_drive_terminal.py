"""Terminal input on a real pseudo-terminal: raw mode, keys, restore, and losing the terminal."""

from __future__ import annotations

import os
import time

import pytest

from snakebot.drive.terminal import TerminalSource
from snakebot.errors import ConfigError

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


def poll_until(source: TerminalSource, count: int) -> list[str]:
    keys: list[str] = []
    deadline = time.monotonic() + 5.0
    while len(keys) < count and time.monotonic() < deadline and source.lost is None:
        keys += source.poll(0.0)
        time.sleep(0.005)
    return keys


def test_raw_mode_reads_keys_at_once_and_close_restores_the_terminal() -> None:
    import pty
    import termios

    master, slave = pty.openpty()
    try:
        before = termios.tcgetattr(slave)
        source = TerminalSource(slave)
        with source:
            mode = termios.tcgetattr(slave)
            assert not mode[3] & (termios.ECHO | termios.ICANON | termios.ISIG)
            assert mode[1] & termios.OPOST  # the display's newlines still work
            os.write(master, b"w\x1b[D \x03")  # no Enter needed; ctrl-c is a key, not a signal
            assert poll_until(source, 4) == ["w", "left", "space", "ctrl-c"]
            assert source.poll(0.0) == []  # nothing more: never blocks
        assert termios.tcgetattr(slave) == before
        source.close()  # idempotent
    finally:
        os.close(master)
        os.close(slave)


def test_closing_the_terminal_is_input_lost() -> None:
    import pty

    master, slave = pty.openpty()
    with TerminalSource(slave) as source:
        os.write(master, b"w")
        assert poll_until(source, 1) == ["w"]
        os.close(master)  # the terminal window closes
        assert poll_until(source, 1) == []
        assert source.lost is not None and source.lost.startswith("the terminal closed")
    os.close(slave)


def test_a_pipe_is_not_a_terminal() -> None:
    read, write = os.pipe()
    try:
        with pytest.raises(
            ConfigError, match=r"^script: standard input is not a terminal: give a key script"
        ):
            TerminalSource(read).open()
    finally:
        os.close(read)
        os.close(write)
