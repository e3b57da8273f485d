"""`--log run.csv` writes `run.csv.json`: what made the log and the unit of every column."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from snakebot import __version__
from snakebot.config import load_robot
from snakebot.telemetry.csv_log import column_names
from snakebot.telemetry.sidecar import read_sidecar, sidecar_path


def test_a_run_log_says_what_made_it(tmp_path: Path) -> None:
    log = tmp_path / "run.csv"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "snakebot",
            "run",
            "--robot",
            "snake12",
            "--gait",
            "sidewinding",
            "--set",
            "amplitude_even=0.4",
            "--duration",
            "1",
            "--log",
            str(log),
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["log_sidecar"] == str(sidecar_path(log))
    sidecar = read_sidecar(log)
    assert sidecar is not None
    robot = load_robot("snake12")
    assert sidecar["snakebot_version"] == __version__
    assert (sidecar["command"], sidecar["backend"], sidecar["rate_hz"]) == ("run", "twin", 100.0)
    assert sidecar["robot"]["name"] == "snake12"
    assert sidecar["robot"]["servo_ids"] == list(robot.servo_ids)
    assert sidecar["robot"]["gains"]["kp_nm_per_rad"] == robot.gains.kp_nm_per_rad
    assert sidecar["robot"]["gain_registers"]["position_p"] == robot.gain_registers.position_p
    assert [j["axis"] for j in sidecar["robot"]["joints"]] == [j.axis for j in robot.joints]
    assert sidecar["gait"]["name"] == "sidewinding"
    assert sidecar["gait"]["params"]["amplitude_even"] == 0.4
    assert sidecar["duration_s"] == 1.0
    columns = sidecar["columns"]
    assert [c["name"] for c in columns] == column_names(12)
    assert log.read_text().splitlines()[0].split(",") == [c["name"] for c in columns]
    units = {c["name"]: c["unit"] for c in columns}
    assert (units["time_s"], units["command_rad_3"], units["velocity_rad_s_11"]) == (
        "s",
        "rad",
        "rad/s",
    )
    assert (units["effort_nm_0"], units["com_z_m"]) == ("N m", "m")


def test_a_drive_log_names_its_gaits(tmp_path: Path) -> None:
    script = tmp_path / "tour.txt"
    script.write_text("0.0 w\n0.5 q\n")
    log = tmp_path / "drive.csv"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "snakebot",
            "drive",
            "--script",
            str(script),
            "--log",
            str(log),
            "--set",
            "amplitude=0.5",
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    sidecar = read_sidecar(log)
    assert sidecar is not None and sidecar["command"] == "drive"
    assert sidecar["gaits"] == [{"name": "serpenoid", "params": {"amplitude": 0.5}}]


def test_snakebot_and_its_cli_parser_do_not_import_the_telemetry_extras() -> None:
    code = (
        "import sys, snakebot, snakebot.cli.main as m; m.build_parser(); "
        "print(sorted(n for n in ('foxglove', 'mcap', 'matplotlib', 'pyarrow') "
        "if n in sys.modules))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[]"
