"""`snakebot run` refuses a --rate the servo bus cannot hold, before any port opens."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from snakebot.cli.main import main
from tests.conftest import edit_robot


def ax_robot(config_dir: Path) -> Path:
    """snake12 built from AX-12A servos on Protocol 1.0 (one Read per servo a cycle)."""
    edit_robot(config_dir, "snake12", 'servo = "XL430-W250"', 'servo = "AX-12A"')
    edit_robot(config_dir, "snake12", "protocol = 2.0", "protocol = 1.0")
    path = edit_robot(
        config_dir,
        "snake12",
        "position_p = 640\nposition_i = 0\nposition_d = 4000",
        "compliance_slope = 32",
    )
    return path


def run(*argv: str) -> int:
    return main(
        [
            "run",
            "--backend",
            "dynamixel",
            "--port",
            "/dev/ttyUSB9",
            "--gait",
            "sidewinding",
            "--duration",
            "1",
            "--dry-run",
            *argv,
        ]
    )


def test_a_rate_the_ax_bus_cannot_hold_is_a_usage_error_with_the_ceiling(
    config_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robot = ax_robot(config_dir)
    assert run("--robot", str(robot), "--rate", "150") == 2
    err = capsys.readouterr().err
    assert "--rate: 150: the servo bus cannot hold 150 Hz: at most 67 Hz" in err
    assert "read by one Read per servo" in err and "12 x 1 ms USB latency" in err
    assert re.search(r"For more: the USB adapter's latency timer at 1 ms.*split the chain", err)
    assert "Traceback" not in err


def test_a_rate_the_bus_holds_goes_ahead(
    config_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robot = ax_robot(config_dir)
    assert run("--robot", str(robot), "--rate", "50") == 0
    assert run("--robot", "snake12", "--rate", "200") == 0  # X-series, Fast Sync Read: ~266 Hz
    capsys.readouterr()


def test_drive_refuses_the_rate_too_before_the_port_opens(
    config_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robot = ax_robot(config_dir)
    script = tmp_path / "keys.txt"
    script.write_text("0.5 q\n")
    code = main(
        [
            "drive",
            "--backend",
            "dynamixel",
            "--port",
            "/dev/ttyUSB9",
            "--robot",
            str(robot),
            "--script",
            str(script),
            "--rate",
            "100",
        ]
    )
    err = capsys.readouterr().err
    assert code == 2, err
    assert "--rate: 100: the servo bus cannot hold 100 Hz: at most 67 Hz" in err
    assert "ttyUSB9" not in err.split("at most")[0]  # refused before any port was opened
