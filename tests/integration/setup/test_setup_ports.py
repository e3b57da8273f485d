"""Robot files and --port cannot make snakebot open a TCP connection or truncate a file.

pyserial opens any URL it knows (socket://, spy://...?file=); snakebot opens device paths, and the
emulator's dxlemu:// URLs only when they come from the command line.
"""

from __future__ import annotations

import socket
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from snakebot.backends.chain import ServoChainBackend
from snakebot.config import load_robot
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.errors import ConfigError
from snakebot.setup import Link
from tests.conftest import edit_robot
from tests.integration.setup.conftest import Bus, Cli


@dataclass
class Listener:
    """A TCP server on localhost that counts the connections it gets (and hangs up on them)."""

    server: socket.socket
    connections: list[tuple[str, int]] = field(default_factory=list)
    stop: threading.Event = field(default_factory=threading.Event)

    @property
    def url(self) -> str:
        host, port = self.server.getsockname()
        return f"socket://{host}:{port}"

    def serve(self) -> None:
        while not self.stop.is_set():
            try:
                client, address = self.server.accept()
            except TimeoutError:
                continue
            self.connections.append(address)
            client.close()


@pytest.fixture
def listener() -> Iterator[Listener]:
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    server.settimeout(0.05)
    tcp = Listener(server)
    thread = threading.Thread(target=tcp.serve, daemon=True)
    thread.start()
    try:
        yield tcp
    finally:
        tcp.stop.set()
        thread.join(timeout=5)
        server.close()


def robot_on_port(config_dir: Path, port: str) -> Path:
    return edit_robot(config_dir, "snake12", 'port = "/dev/ttyUSB0"', f'port = "{port}"')


@pytest.mark.parametrize(
    "command", [["config", "diff"], ["config", "apply", "--yes"], ["calibrate", "--yes"]]
)
def test_a_socket_url_on_the_command_line_is_a_usage_error(
    command: list[str], cli: Cli, config_dir: Path, listener: Listener
) -> None:
    robot = config_dir / "robots" / "snake12.toml"
    code, _, err = cli(*command, "--robot", str(robot), "--port", listener.url)
    assert code == 2
    assert f"refusing to open '{listener.url}'" in err and "--port" in err
    assert listener.connections == []


@pytest.mark.parametrize(
    "command", [["config", "diff"], ["config", "apply", "--yes"], ["calibrate", "--yes"]]
)
def test_a_socket_url_in_the_robot_file_is_refused_naming_file_and_key(
    command: list[str], cli: Cli, config_dir: Path, listener: Listener
) -> None:
    robot = robot_on_port(config_dir, listener.url)
    code, _, err = cli(*command, "--robot", str(robot))
    assert code == 1
    assert f"{robot}: bus.port: refusing to open '{listener.url}'" in err
    assert listener.connections == []


def test_a_spy_url_in_the_robot_file_does_not_truncate_the_file_it_names(
    cli: Cli, config_dir: Path, tmp_path: Path
) -> None:
    victim = tmp_path / "notes.txt"
    victim.write_text("keep me\n")
    robot = robot_on_port(config_dir, f"spy:///dev/null?file={victim}")
    for command in (["config", "diff"], ["calibrate", "--dry-run"]):
        code, _, err = cli(*command, "--robot", str(robot))
        assert victim.read_text() == "keep me\n"
        assert code == 1
        assert "bus.port" in err and "spy://" in err


def test_an_emulator_url_in_the_robot_file_is_refused(config_dir: Path) -> None:
    robot = robot_on_port(config_dir, "dxlemu://bus0")
    with pytest.raises(ConfigError, match="only as a port given directly") as info:
        load_robot(robot)
    assert (info.value.source, info.value.key) == (str(robot), "bus.port")


def test_every_port_opener_refuses_other_urls(listener: Listener, tmp_path: Path) -> None:
    victim = tmp_path / "notes.txt"
    victim.write_text("keep me\n")
    robot = load_robot("snake12")
    for url in (listener.url, f"spy:///dev/null?file={victim}"):
        with pytest.raises(ConfigError, match="is not a serial port"):
            ServoChainBackend(robot, port=url, port_handler_factory=EmulatedPortHandler).connect()
        with pytest.raises(ConfigError, match="is not a serial port"), Link(url, 1_000_000):
            pass
    assert listener.connections == []
    assert victim.read_text() == "keep me\n"


def test_the_emulator_url_still_works_from_the_command_line(
    snake: Bus, cli: Cli, config_dir: Path
) -> None:
    robot = config_dir / "robots" / "snake12.toml"
    code, _, err = cli("config", "diff", "--robot", str(robot), "--port", snake.url)
    assert code in (0, 1), err  # differences or none: it talked to the emulated chain
    assert "refusing" not in err
