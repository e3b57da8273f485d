"""`snakebot log plot | info | export` on logs the CLI wrote."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from snakebot.cli.main import main
from snakebot.telemetry import read_log

SCRIPT = Path(__file__).parents[1] / "drive" / "snake8_forward_left.txt"


def snakebot(*argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "snakebot", *argv], capture_output=True, text=True, timeout=180
    )


@pytest.fixture(scope="module")
def drive_log(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """A scripted drive on the twin: forward, a left turn, stop; its CSV and summary."""
    log = tmp_path_factory.mktemp("drive") / "drive.csv"
    result = snakebot("drive", "--script", str(SCRIPT), "--log", str(log), "--json")
    assert result.returncode == 0, result.stderr
    return log, json.loads(result.stdout)


def test_info_gives_the_drives_own_summary_back_from_the_file(
    drive_log: tuple[Path, dict[str, Any]],
) -> None:
    log, summary = drive_log
    result = snakebot("log", "info", str(log), "--json")
    assert result.returncode == 0, result.stderr
    info = json.loads(result.stdout)
    assert (info["robot"], info["backend"], info["command"]) == ("snake8", "twin", "drive")
    assert info["gait"] == ["serpenoid"]
    assert info["rows"] == summary["control_cycles"]
    assert info["achieved_rate_hz"] == pytest.approx(100.0)
    assert info["late_cycles"] == 0
    assert info["tracking_rms_rad"] == pytest.approx(summary["tracking_rms_rad"], rel=1e-3)
    assert info["max_abs_command_rad"] == pytest.approx(summary["max_abs_command_rad"], abs=1e-5)
    # The log's first row is one cycle after the drive's start: within a cycle's motion.
    assert info["distance_m"] == pytest.approx(summary["distance_m"], abs=2e-3)
    assert info["heading_deg"] == pytest.approx(summary["heading_deg"], abs=1.0)
    text = snakebot("log", "info", str(log))
    assert text.returncode == 0 and "snake8 / serpenoid on twin" in text.stdout


def test_plot_writes_readable_pngs(drive_log: tuple[Path, dict[str, Any]], tmp_path: Path) -> None:
    import matplotlib.image

    log, _ = drive_log
    result = snakebot("log", "plot", str(log), "--out", str(tmp_path / "plots"))
    assert result.returncode == 0, result.stderr
    names = sorted(p.name for p in (tmp_path / "plots").iterdir())
    assert names == ["com_path.png", "efforts.png", "joints.png", "timing.png", "tracking.png"]
    for name in names:
        image = matplotlib.image.imread(tmp_path / "plots" / name)
        assert image.shape[0] >= 400 and image.shape[1] >= 500
        assert image[..., :3].std() > 0.05  # something is drawn, not a blank page
        assert str(tmp_path / "plots" / name) in result.stdout


def test_a_log_without_a_centre_of_mass_plots_without_the_path(
    drive_log: tuple[Path, dict[str, Any]],
    tmp_path: Path,
) -> None:
    lines = drive_log[0].read_text().splitlines()
    hardware = tmp_path / "hardware.csv"  # what a servo chain writes: no CoM
    com = [i for i, name in enumerate(lines[0].split(",")) if name.startswith("com_")]
    rows = [
        ",".join("nan" if i in com else value for i, value in enumerate(line.split(",")))
        for line in lines[1:]
    ]
    hardware.write_text("\n".join([lines[0], *rows]) + "\n")
    result = snakebot("log", "plot", str(hardware))
    assert result.returncode == 0, result.stderr
    folder = tmp_path / "hardware_plots"
    assert sorted(p.name for p in folder.iterdir()) == [
        "efforts.png",
        "joints.png",
        "timing.png",
        "tracking.png",
    ]
    info = json.loads(snakebot("log", "info", str(hardware), "--json").stdout)
    assert info["distance_m"] is None and info["robot"] is None  # no sidecar, no CoM


def test_export_mcap_holds_every_row_and_the_scene(
    drive_log: tuple[Path, dict[str, Any]],
    tmp_path: Path,
) -> None:
    pytest.importorskip("foxglove")
    from tests.integration.telemetry.test_mcap_record import read_mcap

    log, _ = drive_log
    out = tmp_path / "drive.mcap"
    result = snakebot("log", "export", str(log), "--format", "mcap", "--out", str(out))
    assert result.returncode == 0, result.stderr
    topics, schema_names = read_mcap(out)
    table = read_log(log)
    joints = [m for _, m in topics["/joints"]]
    assert len(joints) == len(table.values)
    assert np.allclose([m["position_rad"] for m in joints], table.joints("position_rad"), atol=1e-5)
    assert schema_names["/tf"] == "foxglove.FrameTransforms" and topics["/scene"]
    times_ns = np.array([t for t, _ in topics["/joints"]])
    time_s = table.column("time_s")
    assert np.allclose((times_ns - times_ns[0]) / 1e9, time_s - time_s[0], atol=1e-6)
    assert times_ns[0] > 1.7e18  # the sidecar's start time, not 1970


def test_export_parquet_needs_pyarrow_or_round_trips(
    drive_log: tuple[Path, dict[str, Any]],
    tmp_path: Path,
) -> None:
    log, _ = drive_log
    out = tmp_path / "drive.parquet"
    result = snakebot("log", "export", str(log), "--format", "parquet", "--out", str(out))
    if importlib.util.find_spec("pyarrow") is None:
        assert result.returncode == 1
        assert "pyarrow" in result.stderr and "snakebot[parquet]" in result.stderr
        assert not out.exists()
        return
    assert result.returncode == 0, result.stderr
    import pyarrow.parquet as pq

    table = pq.read_table(out)
    assert table.num_rows == len(read_log(log).values)
    assert json.loads(table.schema.metadata[b"snakebot"])["command"] == "drive"


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        (None, "cannot read telemetry log"),
        ("", "empty telemetry log"),
        ("time_s,cycle\n", "no rows"),
        ("time_s,cycle\n0.0,zero\n", "line 2, column cycle: expected a number"),
        ("a,b\n1,2\n", "missing column"),
    ],
)
def test_a_file_that_is_not_a_log_is_exit_1_naming_it(
    tmp_path: Path, content: str | None, expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "bad.csv"
    if content is not None:
        path.write_text(content)
    for action in (["info"], ["plot"], ["export", "--format", "mcap"]):
        code = main(["log", *action, str(path)])
        stderr = capsys.readouterr().err
        assert code == 1, (action, stderr)
        assert str(path) in stderr and expected in stderr, stderr
        assert "Traceback" not in stderr
