"""The emulator's ``--state-file`` where it cannot be written: exit 1 naming the file, never a
traceback, and the previous state file intact (written atomically: temp file, fsync, rename).

A full disk is made honestly with RLIMIT_FSIZE on the running emulator (``prlimit``): writes
past the limit fail with EFBIG, as they fail with ENOSPC on a full disk (CPython ignores
SIGXFSZ). Read-only places are /proc and a path under a regular file; a device (/dev/full) in
place of the file is refused rather than replaced.
"""

from __future__ import annotations

import json
import os
import resource
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from tests.pty_emulator import Emulator

EMULATE = [sys.executable, "-m", "snakebot", "emulate", "--pty", "--json", "--robot", "snake12"]


def test_a_full_disk_while_serving_is_exit_1_and_keeps_the_previous_state(tmp_path: Path) -> None:
    state = tmp_path / "servos.json"
    proc = subprocess.Popen(
        [*EMULATE, "--fresh", "2", "--state-file", str(state)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        emu = Emulator(proc)
        assert emu.first["waiting"] == 2
        before = state.read_bytes()
        # The state with one more servo is longer than this: its write fails, as on a full disk.
        resource.prlimit(proc.pid, resource.RLIMIT_FSIZE, (len(before), len(before)))
        assert proc.stdin is not None
        proc.stdin.write("plug\n")
        proc.stdin.flush()
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 1, err
    assert f"{state}: cannot save the emulated servos' EEPROM: File too large" in err
    assert "previous state file is kept" in err and "internal error" not in err
    assert state.read_bytes() == before
    assert json.loads(before)["format"] == "snakebot-emulator-state"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["servos.json"]  # no temp file left


@pytest.mark.parametrize("where", ["proc", "under a file", "device"])
def test_a_state_file_that_cannot_be_written_is_exit_1_naming_it(
    tmp_path: Path, where: str
) -> None:
    (tmp_path / "plain").write_text("not a folder\n")
    path = {
        "proc": Path("/proc/snakebot-no-such-folder/servos.json"),
        "under a file": tmp_path / "plain" / "servos.json",
        "device": Path("/dev/full"),
    }[where]
    result = subprocess.run(
        [*EMULATE, "--state-file", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
        stdin=subprocess.DEVNULL,
    )
    assert result.returncode == 1, result.stderr
    assert str(path) in result.stderr and "internal error" not in result.stderr
    if where == "device":
        assert stat.S_ISCHR(os.stat("/dev/full").st_mode)  # refused, not replaced by a file
