"""Scripted drives on the twin (issue 13, "Done when"): the motions and heading changes the keys
ask for, and no commanded target ever steps more than the slew limit."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics, head_yaw_rad
from snakebot.control.safety import SafetyLayer
from snakebot.drive import DriveController, DriveCycle, GaitChoice, ScriptSource, run_drive
from snakebot.gaits.live import LiveGait

pytestmark = pytest.mark.slow

HERE = Path(__file__).parent
RATE_HZ = 100.0


class Trace:
    """Per cycle: time, COM (x, y), head yaw and roll, target, command."""

    def __init__(self) -> None:
        self.rows: list[tuple[float, float, float, float, float]] = []
        self.targets: list[np.ndarray] = []
        self.commands: list[np.ndarray] = []
        self.gaits: list[str] = []

    def __call__(self, cycle: DriveCycle) -> None:
        assert cycle.body is not None
        w, x, y, z = cycle.body.head_quat
        roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        com = cycle.body.com_m
        self.rows.append(
            (cycle.drive_time_s, com[0], com[1], head_yaw_rad(cycle.body.head_quat), roll)
        )
        self.targets.append(cycle.target_rad)
        self.commands.append(cycle.command_rad)
        self.gaits.append(cycle.status.gait)

    def window(self, start_s: float, end_s: float) -> np.ndarray:
        data = np.array(self.rows)
        data[:, 3] = np.unwrap(data[:, 3])
        data[:, 4] = np.unwrap(data[:, 4])
        return data[(data[:, 0] >= start_s) & (data[:, 0] <= end_s)]


def drive(robot_name: str, script: str, gaits: list[str]) -> Trace:
    robot = load_robot(robot_name)
    live = LiveGait(
        robot.joint_count,
        lower_rad=robot.lower_rad,
        upper_rad=robot.upper_rad,
        max_speed_rad_s=robot.max_speed_rad_s,
        period_s=1 / RATE_HZ,
        steer=[j.axis == "yaw" for j in robot.joints],
    )
    trace = Trace()
    with TwinBackend(robot) as twin:
        result = run_drive(
            twin,
            live,
            SafetyLayer.for_robot(robot),
            DriveController(live, [GaitChoice(g) for g in gaits]),
            ScriptSource.load(HERE / script),
            rate_hz=RATE_HZ,
            metrics=RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
            observers=[trace],
        )
    slew = robot.max_speed_rad_s / RATE_HZ
    targets, commands = np.array(trace.targets), np.array(trace.commands)
    np.testing.assert_allclose(commands, targets, rtol=0, atol=1e-12)  # safety changed nothing
    assert np.abs(np.diff(commands, axis=0)).max() <= slew
    np.testing.assert_array_equal(targets[-1], np.zeros(robot.joint_count))  # ends at rest
    assert result.stopped_by == "quit"
    return trace


def heading_change_deg(window: np.ndarray) -> float:
    return math.degrees(window[-1, 3] - window[0, 3])


def travel_angle_to_body_deg(window: np.ndarray) -> float:
    """Angle between the COM's travel and the body's mean axis (head yaw, averaged)."""
    dx, dy = window[-1, 1:3] - window[0, 1:3]
    axis = math.atan2(np.sin(window[:, 3]).mean(), np.cos(window[:, 3]).mean())
    return abs(math.degrees(math.remainder(math.atan2(dy, dx) - axis, 2 * math.pi)))


def distance_m(window: np.ndarray) -> float:
    return float(np.hypot(*(window[-1, 1:3] - window[0, 1:3])))


def test_snake8_drives_forward_then_turns_left_then_stops() -> None:
    trace = drive("snake8", "snake8_forward_left.txt", ["serpenoid"])
    forward = trace.window(2.0, 6.0)
    assert distance_m(forward) > 0.5
    assert travel_angle_to_body_deg(forward) < 20  # head first along the body
    assert abs(heading_change_deg(forward)) < 25  # the head swings, the heading holds
    left = trace.window(8.0, 12.0)
    assert heading_change_deg(left) > 60  # counter-clockwise seen from above: left
    assert distance_m(left) > 0.3


def test_snake12_sidewinds_turns_left_rolls_and_stops() -> None:
    trace = drive("snake12", "snake12_tour.txt", ["sidewinding", "rolling"])
    sidewind = trace.window(2.0, 8.0)
    assert distance_m(sidewind) > 0.5
    assert 60 <= travel_angle_to_body_deg(sidewind) <= 120  # mostly sideways to the body
    turning = trace.window(9.0, 14.0)
    assert heading_change_deg(turning) > 45  # left: counter-clockwise
    assert abs(heading_change_deg(sidewind)) < 25
    rolling = trace.window(17.0, 22.0)
    assert set(trace.gaits[-900:]) == {"rolling"}
    assert distance_m(rolling) > 0.1
    # the head turns over and over (the arc's end is no guide to the body's axis here)
    assert abs(rolling[-1, 4] - rolling[0, 4]) > 2 * math.pi


def test_a_recorded_drive_replays_exactly(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["drive", "--robot", "snake12", "--gaits", "sidewinding,rolling", "--json"]
    record = tmp_path / "drive.rec"
    assert main([*args, "--script", str(HERE / "snake12_tour.txt"), "--record", str(record)]) == 0
    first = json.loads(capsys.readouterr().out)
    assert "replay: snakebot drive --robot snake12" in record.read_text()
    assert main([*args, "--script", str(record)]) == 0
    replay = json.loads(capsys.readouterr().out)
    first.pop("record")
    assert replay == first
    assert first["keys"] == 11 and first["stopped_by"] == "quit"


def test_the_replay_line_a_recording_prints_reproduces_the_drive(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The recording's own replay line, run as written (nothing added), drives what was
    recorded: the gait list, the rate and the drive's settings all travel with it."""
    import shlex

    script = tmp_path / "tour.txt"
    script.write_text("0 1\n0 w\n0 w\n0 w\n0 w\n4 a\n4 a\n6 2\n9 q\n")
    record = tmp_path / "my drive.rec"  # a space: the line must quote it
    assert (
        main(
            [
                "drive",
                "--robot",
                "snake12",
                "--gaits",
                "rolling,sidewinding",
                "--rate",
                "50",
                "--smoothing",
                "0.3",
                "--set",
                "sidewinding.amplitude_even=0.5",
                "--script",
                str(script),
                "--record",
                str(record),
                "--json",
            ]
        )
        == 0
    )
    first = json.loads(capsys.readouterr().out)
    lines = [line for line in record.read_text().splitlines() if line.startswith("# replay: ")]
    assert len(lines) == 1
    words = shlex.split(lines[0].removeprefix("# replay: "))
    assert words[:2] == ["snakebot", "drive"]
    assert main([*words[1:], "--json"]) == 0
    replay = json.loads(capsys.readouterr().out)
    first.pop("record")
    assert replay["gaits"] == ["rolling", "sidewinding"] and replay["rate_hz"] == 50.0
    assert replay["distance_m"] == pytest.approx(first["distance_m"], rel=1e-9, abs=1e-12)
    assert replay == first
