"""The first-day commands against `snakebot emulate --pty` in a subprocess, as a user runs them."""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from tests.integration.setup.conftest import Cli

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


class Emulator:
    """A running `snakebot emulate --pty --json`: its port and its event lines."""

    def __init__(self, proc: subprocess.Popen[str]) -> None:
        self.proc = proc
        self.first = self.event()
        self.port = str(self.first["port"])

    def event(self, timeout_s: float = 20.0) -> dict[str, Any]:
        assert self.proc.stdout is not None
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout_s)
        assert ready, "the emulator printed nothing"
        payload: dict[str, Any] = json.loads(self.proc.stdout.readline())
        return payload

    def command(self, line: str) -> dict[str, Any]:
        assert self.proc.stdin is not None
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        return self.event()


@contextmanager
def emulator(*args: str) -> Iterator[Emulator]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "snakebot", "emulate", "--pty", "--json", *args],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        yield Emulator(proc)
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=10)
        assert proc.returncode == 0, proc.stderr.read() if proc.stderr else ""


def test_apply_then_diff_then_run_on_a_scrambled_chain(cli: Cli) -> None:
    with emulator("--robot", "snake12", "--scramble", "5") as emu:
        port = emu.port
        code, out, _ = cli("config", "diff", "--robot", "snake12", "--port", port)
        assert code == 1 and "baud_rate" in out
        code, _, err = cli("config", "apply", "--robot", "snake12", "--port", port, "--yes")
        assert code == 0, err
        assert cli("config", "diff", "--robot", "snake12", "--port", port)[0] == 0
        code, out, err = cli("run", "--robot", "snake12", "--backend", "dynamixel", "--port",
                             port, "--duration", "1", "--json")
        assert code == 0, err
        assert json.loads(out)["control_cycles"] > 50


def test_fresh_servos_plugged_in_one_at_a_time_keep_their_eeprom(tmp_path: Path, cli: Cli) -> None:
    state = str(tmp_path / "servos.json")
    with emulator("--robot", "snake12", "--fresh", "2", "--state-file", state) as emu:
        assert (emu.first["servo_ids"], emu.first["waiting"]) == ([], 2)
        assert emu.command("plug") == {"event": "plugged", "serial": 1, "id": 1, "baud": 57600,
                                       "waiting": 1}
        code, _, err = cli("config", "assign-id", "--port", emu.port, "--from", "1", "--to", "2",
                           "--robot", "snake12")
        assert code == 0, err
        emu.proc.send_signal(signal.SIGUSR1)
        assert emu.event()["serial"] == 2
        code, out, _ = cli("config", "assign-id", "--port", emu.port, "--from", "1", "--to", "1")
        assert code == 0
        assert out.strip() == "servo ID 1 at 57600 baud is now ID 1 at 1000000 baud"
    with emulator("--robot", "snake12", "--fresh", "2", "--state-file", state) as emu:
        assert (emu.first["servo_ids"], emu.first["waiting"]) == ([1, 2], 0)
        code, out, _ = cli("scan", "--port", emu.port, "--json")
        assert code == 0
        assert [(s["id"], s["baud"]) for s in json.loads(out)["servos"]] == [
            (1, 1_000_000), (2, 1_000_000)]


def test_two_attached_fresh_servos_collide_in_scan(cli: Cli) -> None:
    with emulator("--robot", "snake12", "--fresh", "2", "--attached", "2") as emu:
        code, out, err = cli("scan", "--port", emu.port, "--baud", "57600")
        assert code == 1
        assert "DUPLICATE ID" in out and "ID 1 at 57600 baud" in err
