"""The example plugin installed beside snakebot: its gait is listed, runs on the twin and tunes,
its backend is a `--backend` choice that runs gaits and passes snakebot.testing's contract, all
through the `snakebot` command line in a subprocess (and snakebot.connect), as a user meets it."""

from __future__ import annotations

import contextlib
import json
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import snakebot as api
from snakebot.backends import Simulated
from snakebot.backends.base import Backend
from snakebot.backends.registry import make_backend
from snakebot.config import RobotConfig
from snakebot.errors import BackendError
from snakebot.telemetry.csv_log import read_log
from snakebot.testing import BackendContract, RobotFactory
from tests.plugins.install import (
    environment,
    install_project,
    on_path,
    write_dist_info,
    write_module,
)

ORIGIN = "plugin snakebot-example-plugin 0.1.0"


@pytest.fixture
def site(tmp_path: Path) -> Path:
    folder = tmp_path / "site"
    folder.mkdir()
    install_project(folder)
    return folder


def snakebot(site: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "snakebot", *args],
        capture_output=True,
        text=True,
        env=environment(site),
        timeout=300,
    )


def test_the_plugin_gait_is_listed_with_its_origin_bounds_and_tuning(site: Path) -> None:
    listing = snakebot(site, "gaits", "--json")
    assert listing.returncode == 0, listing.stderr
    gaits = {g["name"]: g for g in json.loads(listing.stdout)}
    assert gaits["serpenoid"]["origin"] == "built-in"
    wave = gaits["standing_wave"]
    assert wave["origin"] == ORIGIN and wave["distribution"] == "snakebot-example-plugin"
    assert wave["default_search"] == ["amplitude", "omega"]
    assert [(p["name"], p["bounds"], p["tunable"]) for p in wave["params"]] == [
        ("amplitude", [0.1, 1.0], True),
        ("omega", [0.5, pytest.approx(4 * np.pi)], True),
        ("spatial_freq", [0.0, pytest.approx(np.pi)], False),
    ]
    text = snakebot(site, "gaits", "standing_wave")
    assert text.returncode == 0, text.stderr
    assert f"standing_wave [{ORIGIN}]" in text.stdout
    assert "tune gait searches by default: amplitude, omega" in text.stdout


def test_the_plugin_gait_runs_on_the_twin(site: Path, tmp_path: Path) -> None:
    log = tmp_path / "wave.csv"
    run = snakebot(
        site, "run", "--gait", "standing_wave", "--set", "amplitude=0.5", "--duration", "3",
        "--log", str(log), "--json",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert summary["gait"] == "standing_wave" and summary["positive_work_j"] > 0.05
    position = read_log(log).joints("position_rad")[100:]  # after the ramp-in
    head, node, middle = position[:, 0], position[:, 2], position[:, 4]
    assert np.ptp(head) > 0.5 and np.ptp(middle) > 0.5  # cos(0) and cos(pi): full swing
    assert np.ptp(node) < 0.5 * np.ptp(head)  # cos(pi/2): the standing wave's node
    assert np.corrcoef(head, middle)[0, 1] < -0.9  # in antiphase, not travelling


def test_the_plugin_gait_tunes_and_its_best_gait_replays(site: Path, tmp_path: Path) -> None:
    best = tmp_path / "best.toml"
    tune = snakebot(
        site, "tune", "gait", "--gait", "standing_wave", "--method", "grid", "--budget", "4",
        "--duration", "1", "--workers", "1", "--out", str(best), "--json", "--quiet",
    )  # fmt: skip
    assert tune.returncode == 0, tune.stderr
    summary = json.loads(tune.stdout)
    assert summary["gait"] == "standing_wave" and summary["evaluations"] == 4
    assert [(d["name"], d["lower"]) for d in summary["searched"]] == [
        ("amplitude", 0.1),
        ("omega", 0.5),
    ]
    replay = snakebot(site, "run", "--gait-file", str(best), "--duration", "1", "--json")
    assert replay.returncode == 0, replay.stderr
    assert json.loads(replay.stdout)["distance_m"] == summary["best"]["metrics"]["distance_m"]


def test_a_broken_plugin_is_reported_and_the_other_gaits_still_run(site: Path) -> None:
    write_module(site, "snakebot_broken_plugin", "import snakebot_missing_dependency\n")
    write_dist_info(
        site,
        "snakebot-broken-plugin",
        "0.0.1",
        {"snakebot.gaits": {"broken_wave": "snakebot_broken_plugin:SPEC"}},
    )
    listing = snakebot(site, "gaits", "--json")
    assert listing.returncode == 0
    assert {"serpenoid", "standing_wave"} <= {g["name"] for g in json.loads(listing.stdout)}
    assert "snakebot: warning: gait 'broken_wave' from plugin snakebot-broken-plugin 0.0.1 " in (
        listing.stderr
    )
    assert "(entry point broken_wave = snakebot_broken_plugin:SPEC)" in listing.stderr
    broken = snakebot(site, "run", "--gait", "broken_wave", "--duration", "0.2")
    assert broken.returncode == 1
    assert "ModuleNotFoundError: No module named 'snakebot_missing_dependency'" in broken.stderr
    fine = snakebot(site, "run", "--gait", "standing_wave", "--duration", "0.2", "--json")
    assert fine.returncode == 0, fine.stderr


def test_clashing_plugins_are_named_and_a_builtin_name_stays_builtin(site: Path) -> None:
    write_dist_info(
        site,
        "snakebot-rival-plugin",
        "2.0",
        {
            "snakebot.gaits": {
                "serpenoid": "snakebot_example_plugin.standing_wave:SPEC",
                "standing_wave": "snakebot_example_plugin.standing_wave:SPEC",
            }
        },
    )
    run = snakebot(site, "run", "--gait", "serpenoid", "--duration", "0.5", "--json")
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["gait"] == "serpenoid"
    assert "snakebot-rival-plugin 2.0 (entry point serpenoid = " in run.stderr
    assert "the built-in is kept" in run.stderr
    clash = snakebot(site, "run", "--gait", "standing_wave", "--duration", "0.5")
    assert clash.returncode == 1
    error = clash.stderr.splitlines()[-1]
    assert "snakebot-rival-plugin 2.0" in error and "snakebot-example-plugin 0.1.0" in error


def test_the_plugin_backend_is_a_backend_choice_and_follows_the_gait(
    site: Path, tmp_path: Path
) -> None:
    usage = snakebot(site, "run", "--help")
    assert usage.returncode == 0 and "kinematic" in usage.stdout
    log = tmp_path / "kinematic.csv"
    run = snakebot(
        site, "run", "--backend", "kinematic", "--gait", "standing_wave", "--duration", "2",
        "--log", str(log), "--json",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert summary["backend"] == "kinematic" and summary["gait"] == "standing_wave"
    assert summary["distance_m"] is None  # no body to measure: no COM, like hardware
    assert summary["tracking_rms_rad"] < 0.01  # it reaches each command within the cycle
    telemetry = read_log(log)
    np.testing.assert_allclose(
        telemetry.joints("position_rad"), telemetry.joints("command_rad"), atol=1e-12
    )
    assert np.ptp(telemetry.joints("position_rad")[:, 0]) > 0.5  # the wave really played


def test_options_the_plugin_backend_does_not_take_are_refused(site: Path) -> None:
    run = snakebot(
        site, "run", "--backend", "kinematic", "--port", "/dev/ttyUSB0", "--duration", "0.2"
    )
    assert run.returncode == 2
    assert "--port does nothing with the kinematic backend" in run.stderr


def test_the_plugin_backend_drives_live_from_a_script(site: Path, tmp_path: Path) -> None:
    script = tmp_path / "keys.txt"
    script.write_text("0 w\n0 w\n1.5 q\n")
    drive = snakebot(site, "drive", "--backend", "kinematic", "--script", str(script), "--json")
    assert drive.returncode == 0, drive.stderr
    summary = json.loads(drive.stdout)
    assert summary["backend"] == "kinematic" and summary["max_abs_command_rad"] > 0.1


def test_the_plugin_backend_through_snakebot_connect(site: Path) -> None:
    with on_path(site):
        assert "kinematic" in api.backend_names()
        with api.connect("snake8", backend="kinematic", max_speed_rad_s=2.0) as snake:
            summary = snake.run("standing_wave", duration_s=3.0, params={"amplitude": 0.3})
            state = snake.read_state()
        assert summary.backend == "kinematic" and summary.gait == "standing_wave"
        assert summary.max_abs_command_rad == pytest.approx(0.3, abs=0.01)
        np.testing.assert_allclose(state.position_rad, 0.0, atol=1e-9)  # ramped out to rest
        unknown = r"unknown backend 'kinematc' \(did you mean 'kinematic'\?\)"
        with pytest.raises(BackendError, match=unknown):
            api.connect("snake8", backend="kinematc")


def test_the_plugin_terrain_is_listed_built_and_driven_on(site: Path, tmp_path: Path) -> None:
    usage = snakebot(site, "run", "--help")
    assert usage.returncode == 0 and "cliff, ridges, with key=value" in " ".join(
        usage.stdout.split()
    )  # the help is the registry's list, the plugin's terrain after the built-ins
    model = tmp_path / "ridges.xml"
    built = snakebot(site, "model", "--terrain", "ridges:count=2", "--out", str(model))
    assert built.returncode == 0, built.stderr
    xml = model.read_text(encoding="utf-8")
    assert 'name="ridge_0"' in xml and 'name="ridge_1"' in xml and "ridge_2" not in xml
    run = snakebot(
        site, "run", "--terrain", "ridges:height_m=0.02,spacing_m=0.1", "--duration", "1",
        "--json",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["distance_m"] is not None
    bad = snakebot(site, "run", "--terrain", "ridges:count=0", "--duration", "0.2")
    assert bad.returncode == 2 and "count" in bad.stderr and "an integer 1..50" in bad.stderr
    with on_path(site), api.connect("snake8", terrain="ridges:count=4") as snake:
        backend = snake.backend
        assert isinstance(backend, Simulated)
        assert backend.model.geom("ridge_3").size[2] == pytest.approx(0.005)  # half of 1 cm


class TestKinematicContract(BackendContract):
    """The plugin's backend, found through its entry point, passes snakebot's own suite."""

    @contextlib.contextmanager
    def backends(self) -> Iterator[RobotFactory]:
        with tempfile.TemporaryDirectory() as folder:
            site = Path(folder)
            install_project(site)
            with on_path(site):

                def make(robot: RobotConfig) -> Backend:
                    return make_backend(robot, "kinematic")

                yield make
