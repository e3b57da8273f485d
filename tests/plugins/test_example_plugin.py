"""The example plugin installed beside snakebot: its gait is listed, runs on the twin and tunes,
all through the `snakebot` command line in a subprocess, as a user would meet it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from snakebot.telemetry.csv_log import read_log
from tests.plugins.install import environment, install_project, write_dist_info, write_module

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
