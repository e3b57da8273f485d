from __future__ import annotations

import json
import math
from pathlib import Path

import mujoco
import pytest

from snakebot.cli.main import main
from snakebot.gaits import save_gait_file
from snakebot.telemetry import read_log
from tests.conftest import edit_robot

SUMMARY_KEYS = {
    "distance_m",
    "displacement_m",
    "speed_mps",
    "heading_deg",
    "body_length_m",
    "joints",
    "cycles",
    "body_lengths_per_cycle",
    "tracking_rms_rad",
    "max_abs_command_rad",
    "cost_of_transport",
    "achieved_rate_hz",
    "overruns",
}


def run_json(capsys: pytest.CaptureFixture[str], *argv: str) -> dict[str, object]:
    assert main(["run", "--json", *argv]) == 0
    out = capsys.readouterr().out
    payload = json.loads(out)
    assert isinstance(payload, dict)
    return payload


def test_run_json_has_the_documented_keys(capsys: pytest.CaptureFixture[str]) -> None:
    summary = run_json(capsys, "--robot", "snake8", "--duration", "4")
    assert set(summary) >= SUMMARY_KEYS
    assert summary["joints"] == 8
    assert summary["cycles"] == pytest.approx(2.0)  # 4 s of a 0.5 Hz serpenoid
    assert float(summary["distance_m"]) > 0.1  # type: ignore[arg-type]
    dx, dy = summary["displacement_m"]  # type: ignore[misc]
    assert math.hypot(dx, dy) == pytest.approx(summary["distance_m"])
    assert summary["max_abs_command_rad"] == pytest.approx(0.4, abs=1e-6)
    assert summary["achieved_rate_hz"] == pytest.approx(100.0)


def test_set_overrides_reach_the_gait(capsys: pytest.CaptureFixture[str]) -> None:
    summary = run_json(capsys, "--duration", "2", "--set", "amplitude=0.2", "--set", "omega=pi/2")
    assert summary["max_abs_command_rad"] == pytest.approx(0.2, abs=1e-6)
    assert summary["cycles"] == pytest.approx(0.5)


def test_gait_file_replays_to_the_same_metrics(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    params = {"amplitude": 0.5, "omega": 2.5, "phase_lag": 0.8}
    gait_file = tmp_path / "tuned.toml"
    save_gait_file(gait_file, "serpenoid", params, {"objective": "speed"})
    direct = run_json(capsys, "--duration", "3", *[f"--set={k}={v}" for k, v in params.items()])
    replay = run_json(capsys, "--duration", "3", "--gait-file", str(gait_file))
    assert replay["distance_m"] == direct["distance_m"]


@pytest.mark.parametrize(
    ("argv", "code", "message"),
    [
        # A bad value typed on the command line is a usage error (2); a missing file is 1.
        (["--set", "omega=abc"], 2, "serpenoid.omega"),
        (["--set", "nope=1"], 2, "nope"),
        (["--set", "omega"], 2, "omega"),
        (["--gait", "moonwalk"], 2, "moonwalk"),
        (["--robot", "snake99"], 1, "known robots"),
        (["--friction", "0.1"], 2, "--friction"),
        (["--rate", "30"], 2, "whole number"),
    ],
)
def test_bad_values_exit_with_a_clear_message(
    argv: list[str], code: int, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["run", "--duration", "1", *argv]) == code
    err = capsys.readouterr().err
    assert err.startswith("snakebot: error:" if code == 1 else ("snakebot", "usage: snakebot run"))
    assert message in err


def test_bad_config_file_exits_1_naming_file_and_key(
    config_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = edit_robot(config_dir, "snake8", "mass_kg = 0.085", "mass_kg = -1")
    assert main(["run", "--robot", str(path), "--duration", "1"]) == 1
    err = capsys.readouterr().err
    assert str(path) in err and "link.mass_kg" in err


def test_usage_errors_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--duration", "-3"]) == 2
    assert main(["fly"]) == 2


def test_log_has_one_row_per_cycle(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "run.csv"
    summary = run_json(capsys, "--duration", "2", "--rate", "50", "--log", str(log))
    data = read_log(log)
    ramp_out_cycles = 50  # 1 s ramp-out at 50 Hz after the 2 s gait
    assert data.values.shape[0] == summary["control_cycles"] + ramp_out_cycles  # type: ignore[operator]
    assert data.column("cycle")[-1] == data.values.shape[0] - 1
    commands = data.joints("command_rad")
    assert abs(commands[-1]).max() < 1e-6  # ramped out to the straight rest pose


def test_human_summary(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--duration", "1"]) == 0
    out = capsys.readouterr().out
    assert "snake8 / serpenoid on twin" in out and "body lengths" in out


def test_model_export_loads_in_mujoco(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "snake12.xml"
    assert main(["model", "--robot", "snake12", "--out", str(out)]) == 0
    model = mujoco.MjModel.from_xml_path(str(out))
    assert model.nu == 12


def test_gaits_lists_every_gait_with_units(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["gaits", "--json"]) == 0
    listing = json.loads(capsys.readouterr().out)
    names = {g["name"] for g in listing}
    assert {
        "serpenoid",
        "compound",
        "sidewinding",
        "rolling",
        "lateral_undulation",
        "linear_progression",
        "turn_in_place",
        "dft",
        "dft_shift",
        "simple",
        "keyframes",
    } <= names
    serpenoid = next(g for g in listing if g["name"] == "serpenoid")
    assert [(p["name"], p["unit"]) for p in serpenoid["params"]] == [
        ("amplitude", "rad"),
        ("omega", "rad/s"),
        ("phase_lag", "rad"),
        ("offset", "rad"),
    ]


def test_video_is_rendered_offscreen(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    video = tmp_path / "run.mp4"
    summary = run_json(capsys, "--duration", "0.4", "--video", str(video))
    assert summary["video"] == str(video)
    assert video.stat().st_size > 1000
    import imageio.v2 as imageio

    frames = imageio.mimread(str(video))
    assert len(frames) >= 10  # 1.4 s (gait + ramp-out) at 25 fps
    assert frames[0].shape[:2] == (480, 640)
