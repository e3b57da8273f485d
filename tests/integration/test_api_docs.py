"""Every python block of docs/api.md runs, each as its own script in an empty folder, as a
reader would paste it: against the twin, and the robot examples against `snakebot emulate
--pty` with backend="dynamixel" (the issue's five-line script included, unchanged but for the
backend and port)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO
from tests.pty_emulator import emulator

DOC = REPO / "docs" / "api.md"
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)
DEVICE = "/dev/ttyUSB0"


def blocks() -> list[str]:
    return BLOCK.findall(DOC.read_text(encoding="utf-8"))


def on_hardware(code: str) -> bool:
    return 'backend="dynamixel"' in code


def run_script(folder: Path, name: str, code: str) -> subprocess.CompletedProcess[str]:
    script = folder / f"{name}.py"
    script.write_text(code, encoding="utf-8")
    return subprocess.run(
        [sys.executable, str(script)], cwd=folder, capture_output=True, text=True, timeout=300
    )


TWIN_BLOCKS = [code for code in blocks() if not on_hardware(code)]


def test_the_doc_has_the_examples_it_promises() -> None:
    codes = blocks()
    assert len(codes) >= 8
    assert 'with snakebot.connect(robot, backend="twin") as snake:' in codes[0]
    assert sum(map(on_hardware, codes)) == 1


@pytest.mark.parametrize("code", TWIN_BLOCKS, ids=[f"block{i}" for i in range(len(TWIN_BLOCKS))])
def test_each_twin_example_runs(code: str, tmp_path: Path) -> None:
    result = run_script(tmp_path, "example", code)
    assert result.returncode == 0, f"{code}\n---\n{result.stderr[-3000:]}"
    assert "Traceback" not in result.stderr


@pytest.mark.pty
@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX")
def test_the_robot_examples_run_over_the_emulated_bus(tmp_path: Path) -> None:
    robot_block = next(code for code in blocks() if on_hardware(code))
    assert DEVICE in robot_block
    five_lines = blocks()[0].replace('backend="twin"', 'backend="dynamixel", port=PORT')
    with emulator("--robot", "snake12") as emu:
        for name, code in (
            ("robot", robot_block.replace(DEVICE, emu.port)),
            ("five_lines", f"PORT = {emu.port!r}\n{five_lines}"),
        ):
            result = run_script(tmp_path, name, code)
            assert result.returncode == 0, f"{code}\n---\n{result.stderr[-3000:]}"
            first = result.stdout.splitlines()[0]
            assert first == "None None"  # nothing measures the body on hardware
        emu.stop()  # and it exits cleanly after serving both scripts
