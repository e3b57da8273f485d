"""The same tools as the rigid twin, on soft bodies: run --json/--log/--video, model, terrain."""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.terrain.cliff import Cliff
from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.telemetry import read_log


def run_json(capsys: pytest.CaptureFixture[str], *argv: str) -> dict[str, object]:
    assert main(["run", "--json", *argv]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert isinstance(payload, dict)
    return payload


def test_run_logs_channels_and_the_com(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "worm.csv"
    summary = run_json(
        capsys, "--robot", "worm", "--gait", "rectilinear", "--duration", "2", "--log", str(log)
    )
    assert summary["joints"] == 18 and summary["log"] == str(log)
    for key in ("speed_mps", "body_lengths_per_cycle", "heading_deg", "travel_angle_deg"):
        assert isinstance(summary[key], float)
    telemetry = read_log(log)
    commands, measured = telemetry.joints("command_rad"), telemetry.joints("position_rad")
    assert commands.shape[1] == measured.shape[1] == 18
    assert np.abs(commands[:, 2::3]).max() == pytest.approx(0.3, abs=0.01)  # axial wave
    assert np.sqrt(((commands - measured) ** 2).mean()) < 0.02  # measured from the lattice
    com_x = telemetry.column("com_x_m")
    assert com_x[-1] - com_x[0] > 0.05


def test_video_shows_the_skin(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    video = tmp_path / "snake.mp4"
    summary = run_json(
        capsys,
        "--robot",
        "snake",
        "--gait",
        "undulation",
        "--duration",
        "0.4",
        "--video",
        str(video),
    )
    assert summary["video"] == str(video)
    import imageio.v2 as imageio

    frames = imageio.mimread(str(video))
    assert len(frames) >= 10 and frames[0].shape[:2] == (480, 640)
    # The skin's flesh colour fills part of the middle of the picture (floor is blue-grey).
    middle = frames[-1][160:320, 160:480].reshape(-1, 3).astype(int)
    flesh = (middle[:, 0] > 150) & (middle[:, 0] > middle[:, 2] + 40)
    assert flesh.mean() > 0.02


def test_model_exports_a_body_with_its_skin(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "worm.xml"
    assert main(["model", "--robot", "worm", "--out", str(out), "--friction", "0.5"]) == 0
    assert "114 springs of 600 N/m" in capsys.readouterr().out
    model = mujoco.MjModel.from_xml_path(str(out))
    assert model.nskin == 1 and model.nu == 114
    assert model.geom("p0_0_geom").friction[0] == pytest.approx(0.5)


@pytest.mark.parametrize(
    ("argv", "code", "message"),
    [
        # A value an option does not take is bad usage (2); a robot the backend cannot drive
        # (a mass-spring body on the servos) and a body/gait mismatch are 1.
        (["--robot", "worm", "--backend", "dynamixel"], 1, "runs on the twin only"),
        (["--robot", "snake8", "--directional", "off"], 2, "mass-spring bodies only"),
        (["--robot", "worm", "--friction", "0.1,0.5"], 2, "isotropic"),
        (["--robot", "worm", "--terrain", "stairs"], 2, "expected one of flat, slope, pegs"),
        (["--robot", "worm", "--terrain", "pegs"], 2, "body lies on flat or cliff"),
        (["--robot", "worm", "--terrain", "cliff:height_m=x"], 2, "height_m"),
        (["--robot", "worm", "--terrain", "cliff:edge_m=0.01"], 2, "flat top"),
        (["--robot", "snake8", "--gait", "rectilinear"], 1, "not whole segments"),
        (
            ["--robot", "snake_yawpitch", "--gait", "rectilinear", "--set", "channels=yaw,pitch"],
            1,
            "axial channel",
        ),
    ],
)
def test_bad_options_exit_1_or_2_with_a_clear_message(
    argv: list[str], code: int, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["run", "--duration", "0.2", *argv]) == code
    err = capsys.readouterr().err
    assert err.startswith("snakebot: error:") and message in err


def test_the_worm_flows_over_the_rounded_cliff(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "cliff.csv"
    summary = run_json(
        capsys,
        "--robot",
        "worm",
        "--gait",
        "rectilinear",
        "--terrain",
        "cliff:edge_m=0.05,height_m=0.04,radius_m=0.02",
        "--duration",
        "6",
        "--log",
        str(log),
    )
    telemetry = read_log(log)
    z = telemetry.column("com_z_m")
    assert z[0] == pytest.approx(0.04 + 0.013, abs=3e-3)  # starts on the plateau
    assert z[-1] == pytest.approx(0.013, abs=3e-3)  # ends on the floor below
    assert telemetry.column("com_x_m")[-1] > 0.05  # past the edge
    assert abs(float(summary["travel_angle_deg"])) < 10  # type: ignore[arg-type]


def test_the_rigid_twin_takes_the_cliff_too(capsys: pytest.CaptureFixture[str]) -> None:
    summary = run_json(capsys, "--robot", "snake8", "--terrain", "cliff", "--duration", "1")
    assert float(summary["distance_m"]) > 0.0  # type: ignore[arg-type]
    with TwinBackend(load_robot("snake8"), terrain=Cliff()) as twin:
        twin.advance(0.1)
        com_z = twin.body_state().com_m[2]
    assert com_z == pytest.approx(Cliff().height_m + 0.022, abs=3e-3)  # on the plateau


def test_gaits_lists_millers_gaits(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["gaits"]) == 0
    out = capsys.readouterr().out
    for name in ("rectilinear", "undulation", "miller_sidewinding"):
        assert name in out


def test_the_soft_body_is_its_own_backend_and_twin_picks_it_by_the_file(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``--backend softbody`` runs a body file; ``--backend twin`` (the default) runs the same
    body the same way, chosen by the file's kind; a servo robot on softbody is refused."""
    argv = ("--robot", "worm", "--gait", "rectilinear", "--duration", "1", "--terrain", "cliff")
    own = run_json(capsys, *argv, "--backend", "softbody")
    picked = run_json(capsys, *argv, "--backend", "twin")
    assert own["backend"] == "softbody" and picked["backend"] == "twin"
    assert own["distance_m"] == picked["distance_m"] and own["distance_m"] is not None
    assert own["contact_fraction"] == picked["contact_fraction"]
    assert main(["run", "--robot", "snake8", "--backend", "softbody", "--duration", "0.2"]) == 1
    assert "snake8: is not a mass-spring body" in capsys.readouterr().err
