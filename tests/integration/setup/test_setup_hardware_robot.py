"""Commands that drive real servos have no default robot: without --robot they stop at usage.

A default (snake8) would hand its servo IDs, joint limits, zero offsets and gains to whatever
chain is on the port. Each command is pointed at an emulated snake12 and must not send it a byte.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.integration.setup.conftest import Bus, Cli

HARDWARE = [
    ("run --backend dynamixel", ["run", "--backend", "dynamixel", "--duration", "1"]),
    ("tune gains --backend dynamixel", ["tune", "gains", "--backend", "dynamixel"]),
    (
        "sysid --record --backend dynamixel",
        ["sysid", "--record", "{tmp}/chirp.csv", "--backend", "dynamixel"],
    ),
    ("config diff", ["config", "diff"]),
    ("config apply", ["config", "apply", "--yes"]),
    ("config assign-id", ["config", "assign-id", "--to", "3"]),
    ("calibrate", ["calibrate", "--yes"]),
    ("servo reboot", ["servo", "reboot", "--id", "3", "--yes"]),
    ("servo reset", ["servo", "reset", "--id", "3", "--yes"]),
    ("servo info", ["servo", "info", "--id", "3"]),
]


@pytest.mark.parametrize(("what", "argv"), HARDWARE, ids=[h[0] for h in HARDWARE])
def test_hardware_commands_without_robot_are_usage_errors_saying_why(
    what: str, argv: list[str], snake: Bus, cli: Cli, tmp_path: Path
) -> None:
    argv = [a.format(tmp=tmp_path) for a in argv]
    before = snake.eeprom()
    code, out, err = cli(*argv, "--port", snake.url)
    assert code == 2, err
    assert f"{what} drives real servos: name their robot with --robot" in err
    assert "no default robot on hardware" in err
    assert out == ""
    assert snake.chain.parser_stats.packets == 0  # not one instruction reached the servos
    assert snake.eeprom() == before
    assert not (tmp_path / "chirp.csv").exists()


@pytest.mark.parametrize(
    "argv",
    [
        ["run", "--duration", "0.5"],
        ["run", "--backend", "sim", "--duration", "0.5"],
        ["model", "--out", "{tmp}/snake.xml"],
        ["sysid", "--record", "{tmp}/chirp.csv", "--duration", "0.5"],
    ],
)
def test_twin_commands_still_default_to_snake8(argv: list[str], cli: Cli, tmp_path: Path) -> None:
    code, _, err = cli(*[a.format(tmp=tmp_path) for a in argv])
    assert code == 0, err


def test_help_says_which_robot_is_the_default(cli: Cli) -> None:
    code, out, _ = cli("run", "--help")
    assert code == 0
    assert "default snake8 on the twin; required with --backend dynamixel" in " ".join(out.split())
