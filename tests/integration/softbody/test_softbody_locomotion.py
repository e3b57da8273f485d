"""Miller's results on the soft bodies, checked through `snakebot run --json` as a user would.

Numbers and commands: docs/soft-bodies.md (tools/softbody_table.py reproduces the table).
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from snakebot.backends.softbody import SoftBodyBackend
from snakebot.cli.main import main
from snakebot.config.body_loader import load_body
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait

pytestmark = pytest.mark.slow


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> dict[str, float]:
    assert main(["run", "--json", *argv]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert isinstance(summary, dict)
    return summary


def test_the_worm_crawls_5x_farther_with_directional_friction_head_first(
    capsys: pytest.CaptureFixture[str],
) -> None:
    scales = run(capsys, "--robot", "worm", "--gait", "rectilinear")
    smooth = run(capsys, "--robot", "worm", "--gait", "rectilinear", "--directional", "off")
    assert scales["duration_s"] == smooth["duration_s"] == 10.0
    assert scales["distance_m"] >= 5 * smooth["distance_m"]
    assert scales["distance_m"] > 0.2  # more than 1.5 body lengths in 10 s
    assert abs(scales["travel_angle_deg"]) < 10  # head first along its own axis
    assert scales["displacement_m"][0] > 0  # type: ignore[index]


def test_the_snake_undulates_head_first(capsys: pytest.CaptureFixture[str]) -> None:
    summary = run(capsys, "--robot", "snake", "--gait", "undulation")
    assert summary["distance_m"] > 0.1
    assert abs(summary["travel_angle_deg"]) < 20


def test_the_snake_sidewinds_mostly_sideways(capsys: pytest.CaptureFixture[str]) -> None:
    summary = run(capsys, "--robot", "snake", "--gait", "miller_sidewinding")
    assert summary["distance_m"] > 0.1
    assert abs(summary["travel_angle_deg"]) >= 60
    assert summary["contact_fraction"] < 0.4  # the vertical wave lifts most of the body


def test_the_rigid_twins_gaits_drive_a_yaw_pitch_body(capsys: pytest.CaptureFixture[str]) -> None:
    forward = run(capsys, "--robot", "snake_yawpitch", "--gait", "lateral_undulation")
    assert forward["joints"] == 20 and forward["distance_m"] > 0.05
    assert abs(forward["travel_angle_deg"]) < 20
    sideways = run(capsys, "--robot", "snake_yawpitch", "--gait", "sidewinding")
    assert abs(sideways["travel_angle_deg"]) > 60


def _tail_free_vibration(damping: float) -> float:
    """RMS (rad) of the tail's yaw motion that is not at the drive frequency, after 4 s."""
    body = load_body("snake")
    body = replace(body, springs=replace(body.springs, damping=damping, preset=""))
    gait = make_gait("undulation", body.joint_count)
    rows: list[tuple[float, np.ndarray]] = []
    with SoftBodyBackend(body) as backend:

        def sample(cycle: int, gait_time_s: float) -> None:
            rows.append((gait_time_s, backend.read_state().position_rad[0::3]))

        metrics = RunMetrics(body.joint_count, body.body_length_m, body.total_mass_kg)
        plan = RunPlan(10.0, ramp_out=False)
        run_gait(backend, gait, SafetyLayer.for_robot(body), plan, metrics, on_cycle=sample)
    times = np.array([t for t, _ in rows if t >= 4.0])
    yaw = np.array([y for t, y in rows if t >= 4.0])
    drive = np.exp(1j * 2 * math.pi * times)
    amplitude = 2 * (yaw * drive.conj()[:, None]).mean(axis=0)
    free = yaw - (amplitude[None, :] * drive[:, None]).real
    return float(np.sqrt((free[:, -3:] ** 2).mean()))


def test_less_damping_leaves_the_tail_vibrating() -> None:
    millers = _tail_free_vibration(3.5)  # the snake's damping ratio 2.5
    light = _tail_free_vibration(0.2)  # damping ratio 0.14
    assert light > 1.5 * millers
