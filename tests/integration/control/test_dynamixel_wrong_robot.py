"""`snakebot run --backend dynamixel` with an 8-servo robot file on a 12-servo chain refuses.

Two processes, as a user runs them: `snakebot emulate --pty` with snake12's twelve servos, and
`snakebot run` told the robot is snake8.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


def run(port: str, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "snakebot",
            "run",
            "--backend",
            "dynamixel",
            "--port",
            port,
            "--robot",
            "snake8",
            "--duration",
            "0.5",
            "--json",
            *extra,
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )


def test_a_robot_file_naming_fewer_servos_than_the_bus_holds_is_refused() -> None:
    with emulator("--robot", "snake12") as emu:
        refused = run(emu.port)
        allowed = run(emu.port, "--allow-extra-servos")
    assert refused.returncode == 1, refused.stderr
    assert "unexpected servo ID(s) on the bus: 9 (XL430-W250), 10 (XL430-W250), 11" in (
        refused.stderr
    )
    assert "--allow-extra-servos" in refused.stderr
    assert "Traceback" not in refused.stderr
    assert allowed.returncode == 0, allowed.stderr
    assert "servo ID(s) 9, 10, 11, 12 are on the bus but not in the robot file" in allowed.stderr
