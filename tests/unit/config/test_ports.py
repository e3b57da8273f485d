"""The one rule for opening ports: device paths anywhere, the emulator's URLs only if allowed."""

from __future__ import annotations

import pytest

from snakebot.config.ports import EMULATOR_SCHEME, check_port
from snakebot.emulation.registry import SCHEME
from snakebot.errors import ConfigError


def test_the_emulator_scheme_is_the_emulators() -> None:
    assert EMULATOR_SCHEME == SCHEME


@pytest.mark.parametrize("port", ["/dev/ttyUSB0", "/dev/pts/7", "COM3", "/dev/tty.usbserial-A1"])
@pytest.mark.parametrize("allow_emulator", [True, False])
def test_device_paths_are_accepted(port: str, allow_emulator: bool) -> None:
    assert check_port(port, allow_emulator=allow_emulator) == port


@pytest.mark.parametrize("port", ["dxlemu://bus0", "dxlemu://snake?time=wall", "DXLEMU://x"])
def test_emulator_urls_only_where_allowed(port: str) -> None:
    assert check_port(port) == port
    with pytest.raises(ConfigError, match="only as a port given directly") as info:
        check_port(port, source="robot.toml", key="bus.port", allow_emulator=False)
    assert (info.value.source, info.value.key) == ("robot.toml", "bus.port")


@pytest.mark.parametrize(
    "port",
    [
        "socket://127.0.0.1:7777",
        "spy:///dev/ttyUSB0?file=/home/me/.bashrc",
        "rfc2217://host:2217",
        "loop://",
        "hwgrep://FTDI",
        "alt:///dev/ttyUSB0?class=PosixPollSerial",
        "Socket://127.0.0.1:7777",
    ],
)
def test_other_urls_are_refused_everywhere(port: str) -> None:
    for allow in (True, False):
        with pytest.raises(ConfigError, match="is not a serial port") as info:
            check_port(port, source="--port", allow_emulator=allow)
        assert info.value.source == "--port"


@pytest.mark.parametrize("port", ["", "   ", "/dev/tty\nUSB0", "/dev/tty\x00"])
def test_empty_or_control_characters_are_refused(port: str) -> None:
    with pytest.raises(ConfigError):
        check_port(port)
