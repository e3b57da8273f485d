"""A minute of hardware in the loop over a real pty, with two CPU-bound processes beside it.

`snakebot run --backend dynamixel` drives `snakebot emulate --pty --physics`, each in its own
process, as users run them (tools/soak_pty.py). Opt-in: `pytest -m soak` (CI runs it in a step of
its own). SNAKEBOT_SOAK_S sets the duration (default 60 s of real time). It never skips itself: a
machine too busy to hold the rate fails it, with the measured rate and the longest time the kernel
kept the run or the emulator waiting for a CPU, so a starved run is told apart from a bug.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

TOOL = Path(__file__).resolve().parents[3] / "tools" / "soak_pty.py"
STARVED_S = 0.1  # a runnable wait this long breaks the 100 ms watchdog whatever the code does

pytestmark = [
    pytest.mark.soak,
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


def test_a_minute_of_hardware_in_the_loop_under_load_loses_nothing() -> None:
    duration = float(os.environ.get("SNAKEBOT_SOAK_S", "60"))
    command = [
        sys.executable,
        str(TOOL),
        "--duration",
        str(duration),
        "--rate",
        "50",
        "--load",
        "2",
        "--json",
    ]
    done = subprocess.run(command, capture_output=True, text=True, timeout=duration * 5 + 300)
    report = json.loads(done.stdout)
    starved = (
        f"; the machine kept the run or the emulator from a CPU for "
        f"{report['longest_cpu_wait_s']:.2f} s (more than two CPU-bound processes can)"
        if report["longest_cpu_wait_s"] >= STARVED_S
        else ""
    )
    assert report["ok"], f"{report['log_rows']} rows in {duration:g} s{starved}: " + json.dumps(
        report, indent=1
    )
    assert report["log_rows"] >= 0.9 * 50 * duration
    assert report["emulator_bus"]["watchdog_trips"] == 0
    assert done.returncode == 0
