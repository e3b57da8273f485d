"""The first-day commands against `snakebot emulate --pty` in a subprocess, as a user runs them."""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import pytest

from tests.integration.setup.conftest import Cli
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


def test_apply_then_diff_then_run_on_a_scrambled_chain(cli: Cli) -> None:
    with emulator("--robot", "snake12", "--scramble", "5") as emu:
        port = emu.port
        code, out, _ = cli("config", "diff", "--robot", "snake12", "--port", port)
        assert code == 1 and "baud_rate" in out
        code, _, err = cli("config", "apply", "--robot", "snake12", "--port", port, "--yes")
        assert code == 0, err
        assert cli("config", "diff", "--robot", "snake12", "--port", port)[0] == 0
        code, out, err = cli(
            "run",
            "--robot",
            "snake12",
            "--backend",
            "dynamixel",
            "--port",
            port,
            "--gait",
            "sidewinding",
            "--duration",
            "1",
            "--json",
        )
        assert code == 0, err
        assert json.loads(out)["control_cycles"] > 50


def test_fresh_servos_plugged_in_one_at_a_time_keep_their_eeprom(tmp_path: Path, cli: Cli) -> None:
    state = str(tmp_path / "servos.json")
    with emulator("--robot", "snake12", "--fresh", "2", "--state-file", state) as emu:
        assert (emu.first["servo_ids"], emu.first["waiting"]) == ([], 2)
        assert emu.command("plug") == {
            "event": "plugged",
            "serial": 1,
            "id": 1,
            "baud": 57600,
            "waiting": 1,
        }
        code, _, err = cli(
            "config",
            "assign-id",
            "--port",
            emu.port,
            "--from",
            "1",
            "--to",
            "2",
            "--robot",
            "snake12",
        )
        assert code == 0, err
        emu.proc.send_signal(signal.SIGUSR1)
        assert emu.event()["serial"] == 2
        code, out, _ = cli(
            "config",
            "assign-id",
            "--port",
            emu.port,
            "--from",
            "1",
            "--to",
            "1",
            "--robot",
            "snake12",
        )
        assert code == 0
        assert out.strip() == "servo ID 1 at 57600 baud is now ID 1 at 1000000 baud"
    with emulator("--robot", "snake12", "--fresh", "2", "--state-file", state) as emu:
        assert (emu.first["servo_ids"], emu.first["waiting"]) == ([1, 2], 0)
        code, out, _ = cli("scan", "--port", emu.port, "--protocol", "2", "--json")
        assert code == 0
        assert [(s["id"], s["baud"]) for s in json.loads(out)["servos"]] == [
            (1, 1_000_000),
            (2, 1_000_000),
        ]


def test_two_attached_fresh_servos_collide_in_scan(cli: Cli) -> None:
    with emulator("--robot", "snake12", "--fresh", "2", "--attached", "2") as emu:
        code, out, err = cli("scan", "--port", emu.port, "--baud", "57600", "--protocol", "2")
        assert code == 1
        assert "DUPLICATE ID" in out and "ID 1 at 57600 baud" in err


def test_scan_finds_an_ax_chain_and_an_x_servo_on_one_pty(cli: Cli) -> None:
    with emulator("--robot", "snake12-ax12a", "--also", "XL430-W250:20") as emu:
        code, out, err = cli("scan", "--port", emu.port, "--ids", "0-21", "--json")
    assert code == 0, err
    report = json.loads(out)
    found = [(s["id"], s["protocol"], s["model"]) for s in report["servos"]]
    assert found == [(20, 2.0, "XL430-W250"), *((i, 1.0, "AX-12A") for i in range(1, 13))]
    assert report["mixed"] is True
    assert "servos of two protocols share this port" in err
