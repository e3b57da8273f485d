"""An emulator whose parent died stops by itself; one whose parent lives on keeps serving.

The rule (docs/hardware.md): ``snakebot emulate`` stops, saving its state file, when the pipe on
its stdin ends *and* the process that started it has exited. Tests and scripts start it with a
pipe on stdin; a killed test run used to leave it serving until someone sent SIGTERM.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]

PARENT = """
import json, os, subprocess, sys
err = open(sys.argv[1], "w")
child = subprocess.Popen(
    [sys.executable, "-m", "snakebot", "emulate", "--pty", "--json", "--robot", "snake8",
     "--fresh", "0", "--state-file", sys.argv[2]],
    stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=err, text=True,
)
first = json.loads(child.stdout.readline())
print(json.dumps({"pid": child.pid, "port": first["port"]}), flush=True)
if sys.argv[3] == "close-stdin-and-live":
    child.stdin.close()
    sys.stdin.readline()  # until the test says so
    child.terminate()
    child.wait()
os._exit(0)  # as if killed: nothing is closed or waited for
"""


def gone(pid: int) -> bool:
    """The process exited (a zombie nobody reaped counts: it serves nothing)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return True
    except OSError:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        return False
    return state in ("Z", "X")


def start_parent(tmp_path: Path, mode: str) -> tuple[subprocess.Popen[str], dict[str, object]]:
    parent = subprocess.Popen(
        [
            sys.executable,
            "-c",
            PARENT,
            str(tmp_path / "err.txt"),
            str(tmp_path / "servos.json"),
            mode,
        ],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert parent.stdout is not None
    line = parent.stdout.readline()  # start-up imports: slow on a loaded machine
    assert line, "the parent printed nothing"
    return parent, json.loads(line)


def test_an_emulator_whose_parent_died_stops_and_saves_its_state(tmp_path: Path) -> None:
    parent, child = start_parent(tmp_path, "die")
    parent.wait(timeout=30)
    pid = int(str(child["pid"]))
    deadline = time.monotonic() + 20
    while not gone(pid):
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGTERM)  # leave nothing behind
            raise AssertionError("the orphaned emulator kept serving")
        time.sleep(0.1)
    assert not Path(str(child["port"])).exists()  # the pty is gone with it
    err = (tmp_path / "err.txt").read_text()
    assert "stdin closed and the process that started it" in err
    assert "Traceback" not in err
    assert (tmp_path / "servos.json").exists()  # stopped as on SIGTERM: state saved


def test_an_emulator_whose_stdin_closed_keeps_serving_while_its_parent_lives(
    tmp_path: Path,
) -> None:
    parent, child = start_parent(tmp_path, "close-stdin-and-live")
    try:
        time.sleep(1.5)  # several of the emulator's 0.1 s checks
        assert not gone(int(str(child["pid"])))
        assert Path(str(child["port"])).exists()
    finally:
        assert parent.stdin is not None
        parent.stdin.write("done\n")
        parent.stdin.flush()
        parent.wait(timeout=30)
