"""The replay line a `--record` file carries: every option that changes what the drive does."""

from __future__ import annotations

import shlex
from pathlib import Path

from snakebot.cli.drive_cmd import replay_command
from snakebot.cli.main import build_parser


def replay_of(*argv: str) -> list[str]:
    args = build_parser().parse_args(["drive", *argv])
    return shlex.split(replay_command(args, Path("tour.rec")))


def test_a_hardware_drive_replays_on_the_same_port_with_the_same_settings() -> None:
    words = replay_of(
        "--robot",
        "my robots/limp12.toml",
        "--backend",
        "dynamixel",
        "--port",
        "/dev/ttyUSB0",
        "--baud",
        "1000000",
        "--allow-extra-servos",
        "--gaits",
        "rolling",
        "--set",
        "amplitude=0.4",
        "--rate",
        "62.5",
        "--transition",
        "2",
        "--log",
        "x.csv",
        "--record",
        "tour.rec",
    )
    assert words == [
        "snakebot",
        "drive",
        "--robot",
        "my robots/limp12.toml",
        "--backend",
        "dynamixel",
        "--port",
        "/dev/ttyUSB0",
        "--baud",
        "1000000",
        "--allow-extra-servos",
        "--gaits",
        "rolling",
        "--set",
        "amplitude=0.4",
        "--rate",
        "62.5",
        "--transition",
        "2.0",
        "--script",
        "tour.rec",
    ]


def test_a_twin_drive_names_its_robot_and_friction_and_leaves_pacing_out() -> None:
    words = replay_of("--friction", "0.2,1.5", "--realtime", "--smoothing", "0.25")
    assert words == [
        "snakebot",
        "drive",
        "--robot",
        "snake8",
        "--friction",
        "0.2,1.5",
        "--rate",
        "100.0",
        "--smoothing",
        "0.25",
        "--script",
        "tour.rec",
    ]
