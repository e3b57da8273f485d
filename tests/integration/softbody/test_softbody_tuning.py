"""`snakebot tune gait` over a soft body's muscle parameters, replayed by `snakebot run`."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from snakebot.cli.main import main


@pytest.mark.slow
def test_tuned_rectilinear_gait_beats_the_default_and_replays(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    gait_file = tmp_path / "worm.toml"
    argv = [
        "tune",
        "gait",
        "--robot",
        "worm",
        "--gait",
        "rectilinear",
        "--method",
        "grid",
        "--params",
        "amplitude,waves",
        "--budget",
        "4",
        "--duration",
        "3",
        "--quiet",
        "--json",
        "--out",
        str(gait_file),
    ]
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["engine"] == "processes"  # the normal runner, not mujoco.batch
    assert summary["evaluations"] == summary["feasible_evaluations"] == 4
    best = summary["best"]
    assert best["value"] >= summary["baseline"]["value"]
    assert {"travel_angle_deg", "contact_fraction"} <= set(best["metrics"])
    assert (
        main(["run", "--json", "--robot", "worm", "--gait-file", str(gait_file), "--duration", "3"])
        == 0
    )
    replay = json.loads(capsys.readouterr().out)
    assert replay["distance_m"] == pytest.approx(best["metrics"]["distance_m"], rel=1e-9)


def test_a_body_gait_faster_than_the_muscles_is_not_playable(
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = [
        "tune",
        "gait",
        "--robot",
        "worm",
        "--gait",
        "rectilinear",
        "--method",
        "grid",
        "--params",
        "omega,waves",
        "--bounds",
        "omega=60:80",
        "--set",
        "amplitude=0.4",
        "--budget",
        "4",
        "--duration",
        "1",
        "--quiet",
        "--json",
    ]
    assert main(argv) == 1  # 0.4 strain at 60-80 rad/s asks the muscles for 24-32 /s, not 20
    summary = json.loads(capsys.readouterr().out)
    assert summary["feasible_evaluations"] == 0
    assert summary["best"]["violations"]["speed_excess"] > 0
