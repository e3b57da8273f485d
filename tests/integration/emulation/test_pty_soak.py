"""A minute of hardware in the loop over a real pty, with two CPU-bound processes beside it.

`snakebot run --backend dynamixel` drives `snakebot emulate --pty --physics`, each in its own
process, as users run them (tools/soak_pty.py). Deselect locally with `-m "not soak"`; CI runs it.
SNAKEBOT_SOAK_S sets the duration (default 60 s of real time). A failure while the kernel kept
the run or the emulator waiting for a CPU for 0.1 s or more (the machine is busier than two
CPU-bound processes make it) is reported as a skip with the figures, not as a pass.
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
    command = [sys.executable, str(TOOL), "--duration", str(duration), "--rate", "50",
               "--load", "2", "--json"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=duration * 5 + 300)
    report = json.loads(done.stdout)
    if not report["ok"] and report["longest_cpu_wait_s"] >= STARVED_S:
        pytest.skip(f"the machine kept the run or the emulator from a CPU for "
                    f"{report['longest_cpu_wait_s']:.2f} s (more than two CPU-bound processes "
                    f"can): {report['failures']}")
    assert report["ok"], json.dumps(report, indent=1)
    assert report["log_rows"] >= 0.9 * 50 * duration
    assert report["emulator_bus"]["watchdog_trips"] == 0
    assert done.returncode == 0
