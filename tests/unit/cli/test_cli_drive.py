"""`snakebot drive` errors a user can fix: exit 1 (or 2 for usage) with what was expected."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from snakebot.cli.main import main
from snakebot.telemetry import read_log


def drive(tmp_path: Path, script: str, *argv: str) -> int:
    path = tmp_path / "keys.txt"
    path.write_text(script)
    return main(["drive", "--script", str(path), *argv])


@pytest.mark.parametrize(
    ("argv", "code", "message"),
    [
        # Bad values typed on the command line are usage errors (2), like argparse's own.
        (["--gaits", "slither"], 2, "unknown gait 'slither'"),
        (
            ["--gaits", "sidewinding,rolling", "--set", "amplitude_even=0.3"],
            2,
            "amplitude_even=0.3: expected GAIT.KEY=VALUE with GAIT one of sidewinding, rolling",
        ),
        (["--gaits", "serpenoid", "--set", "omega=fast"], 2, "expected a number in rad/s"),
        (["--gaits", "keyframes", "--set", "advance=error"], 1, "keyframes: cannot be driven live"),
        (["--smoothing", "-1"], 2, "--smoothing: expected seconds >= 0"),
        (["--record", "/proc/nope/keys.rec"], 1, "cannot write the recording"),
    ],
)
def test_bad_options_exit_1_or_2_and_say_what_was_expected(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], code: int, message: str
) -> None:
    assert drive(tmp_path, "0 q\n", *argv) == code
    assert message in capsys.readouterr().err


def test_a_bad_script_line_is_named_by_file_and_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert drive(tmp_path, "# keys\n0 w\n1 jump\n") == 1
    err = capsys.readouterr().err
    assert f"{tmp_path / 'keys.txt'}:3: unknown key 'jump'" in err


def test_script_and_gamepad_together_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["drive", "--script", "x.txt", "--gamepad"]) == 2
    assert "not allowed with argument" in capsys.readouterr().err


def test_a_short_drive_prints_its_summary_and_keeps_its_log(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "drive.csv"
    code = drive(
        tmp_path,
        "0 w\n0 w\n0 w\n0 w\n3 q\n",
        "--robot",
        "snake8",
        "--log",
        str(log),
        "--set",
        "amplitude=0.3",
        "--json",
    )
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["gaits"] == ["serpenoid"] and summary["stopped_by"] == "quit"
    assert summary["keys"] == 5 and summary["distance_m"] > 0.05
    assert summary["max_abs_command_rad"] <= 0.3 + 1e-9
    assert summary["physics"]["warnings"] == []  # the twin's physics health (docs/physics.md)
    data = read_log(log)
    assert data.values.shape[0] == summary["control_cycles"]


def test_a_script_without_q_stops_at_its_end(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert drive(tmp_path, "0 w\n1 w\n", "--robot", "snake8") == 0
    out = capsys.readouterr().out
    assert "stopped by end of script" in out
