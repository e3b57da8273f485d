"""The ros2 extra stays optional: `import snakebot` never loads rclpy, and the command says what
to install when it is missing."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import snakebot
from snakebot.cli.main import main

PACKAGE = Path(snakebot.__file__).resolve().parent
ROS_MODULES = ("rclpy", "sensor_msgs", "geometry_msgs", "trajectory_msgs", "diagnostic_msgs")


def test_importing_snakebot_and_its_ros2_package_and_the_cli_loads_no_rclpy() -> None:
    code = (
        "import sys, snakebot, snakebot.ros2, snakebot.ros2.serve, snakebot.cli.main as m; "
        "m.build_parser(); "
        f"loaded = [n for n in {ROS_MODULES!r} if n in sys.modules]; "
        "assert not loaded, loaded"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=PACKAGE.parent)


def test_only_the_node_module_imports_ros() -> None:
    from tests.unit.test_layering import imported

    users = {
        path.relative_to(PACKAGE.parent).as_posix()
        for path in PACKAGE.rglob("*.py")
        if any(name.split(".")[0] in ROS_MODULES for name in imported(path))
    }
    assert users == {"snakebot/ros2/node.py"}


def test_without_the_extra_the_command_names_the_install_line_and_exits_1(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "rclpy", None)  # as if ros-rclpy were not installed
    assert main(["ros2", "--robot", "snake12"]) == 1
    err = capsys.readouterr().err
    assert "pip install 'snakebot[ros2]'" in err and "rclpy is not installed" in err
