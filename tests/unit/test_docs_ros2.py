"""docs/ros2.md stays true: its topic tables are the code's, its URDF and launch example name
the plugin's real parameters and the node's joints and topics, its Python snippet runs."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
import types
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from snakebot.config import load_robot
from snakebot.session import DEFAULT_RATE_HZ
from snakebot.telemetry import ros2_msgs

DOC = Path(__file__).resolve().parents[2] / "docs" / "ros2.md"
TEXT = DOC.read_text(encoding="utf-8")
HAS_NODE = importlib.util.find_spec("snakebot.ros2") is not None
needs_node = pytest.mark.skipif(not HAS_NODE, reason="snakebot ros2 is not in this tree")

# joint_state_topic_hardware_interface's hardware parameters (its on_init reads these).
PLUGIN = "joint_state_topic_hardware_interface/JointStateTopicSystem"
PLUGIN_PARAMS = {
    "joint_commands_topic",
    "joint_states_topic",
    "trigger_joint_command_threshold",
    "sum_wrapped_joint_states",
    "enable_command_limiting",
}


def block(language: str, index: int = 0) -> str:
    found = re.findall(rf"^```{language}\n(.*?)^```", TEXT, re.S | re.M)
    return str(found[index])


def table(after: str) -> list[list[str]]:
    """The rows of the first table after the line ``after``: cells without backticks."""
    lines = TEXT[TEXT.index(after) :].splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("|"))
    rows = []
    for line in lines[start + 2 :]:
        if not line.startswith("|"):
            break
        rows.append([cell.strip().strip("`") for cell in line.strip("|").split("|")])
    return rows


def test_the_recording_table_is_what_the_recorder_writes() -> None:
    rows = table("two that only a recording has:")
    assert {row[0]: row[1] for row in rows} == ros2_msgs.TOPIC_TYPES


@needs_node
def test_the_topic_table_is_the_nodes_interface() -> None:
    from snakebot.ros2 import topics

    rows = {row[0]: row for row in table("## Topics")}
    assert set(rows) == {topic.name for topic in topics.TOPICS}
    for topic in topics.TOPICS:
        _, kind, direction, qos, _ = rows[topic.name]
        assert kind == topic.type
        assert direction == topic.direction
        reliability = topic.qos.reliability.replace("_", " ")
        assert qos == f"{reliability}, keep last {topic.qos.depth}"
    assert f"default {topics.DEFAULT_COMMAND_TIMEOUT_S:g} s" in TEXT
    assert f"{topics.DIAGNOSTICS_PERIOD_S:g} Hz" in rows["diagnostics"][4]


@needs_node
def test_the_loopback_settings_are_the_nodes() -> None:
    from snakebot.ros2 import loopback_environment

    exports = dict(re.findall(r"^export (\w+)=(.*)$", block("sh", -1), re.M))
    settings = loopback_environment()
    assert set(exports) == set(settings)
    for key in ("ROS_AUTOMATIC_DISCOVERY_RANGE", "RMW_IMPLEMENTATION"):
        assert exports[key] == settings[key]
    command = re.search(r"\$\(python -c '(.*)'\)", exports["FASTDDS_DEFAULT_PROFILES_FILE"])
    assert command is not None
    printed = subprocess.run(
        [sys.executable, "-c", command.group(1)], capture_output=True, text=True, check=True
    )
    assert Path(printed.stdout.strip()) == Path(settings["FASTDDS_DEFAULT_PROFILES_FILE"])
    assert Path(printed.stdout.strip()).is_file()


def hardware_params(control: ET.Element) -> dict[str, str]:
    hardware = control.find("hardware")
    assert hardware is not None
    plugin = hardware.find("plugin")
    assert plugin is not None and (plugin.text or "").strip() == PLUGIN
    params = {p.get("name", ""): (p.text or "") for p in hardware.findall("param")}
    assert set(params) <= PLUGIN_PARAMS
    assert float(params["trigger_joint_command_threshold"]) < 0  # publishes every update
    return params


def test_the_urdf_tag_names_the_plugins_parameters_and_the_nodes_topics() -> None:
    control = ET.fromstring(block("xml").replace("<!-- ... the same for joint1 .. joint7 -->", ""))
    params = hardware_params(control)
    assert params["joint_states_topic"] == "/snake/joint_states"
    assert params["joint_commands_topic"] == "/snake/joint_commands"
    assert "__ns:=/snake" in TEXT
    joint = control.find("joint")
    assert joint is not None and joint.get("name") == "joint0"
    assert [c.get("name") for c in joint.findall("command_interface")] == ["position"]


class _Action:
    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.args, self.kwargs = args, kwargs


def _launch_namespace(folder: Path) -> dict[str, Any]:
    """Run the launch example's module body with stand-ins for launch and launch_ros."""
    stand_ins = {
        "launch": types.SimpleNamespace(LaunchDescription=_Action),
        "launch.actions": types.SimpleNamespace(ExecuteProcess=_Action),
        "launch_ros.actions": types.SimpleNamespace(Node=_Action),
    }
    saved = {name: sys.modules.get(name) for name in stand_ins}
    sys.modules.update(stand_ins)  # type: ignore[arg-type]
    try:
        namespace: dict[str, Any] = {"__file__": str(folder / "snake_control.launch.py")}
        exec(compile(block("python", 0), "snake_control.launch.py", "exec"), namespace)
    finally:
        for name, module in saved.items():
            if module is None:
                sys.modules.pop(name, None)
            else:
                sys.modules[name] = module
    return namespace


def test_the_launch_example_builds_snake8s_urdf_and_starts_the_node_in_its_namespace(
    tmp_path: Path,
) -> None:
    yaml = pytest.importorskip("yaml")
    launch = _launch_namespace(tmp_path)
    robot = load_robot("snake8")
    names = [f"joint{i}" for i in range(robot.joint_count)]
    assert launch["JOINTS"] == names
    assert launch["LINK_M"] == robot.link.length_m
    assert np.all(robot.lower_rad == launch["LOWER_RAD"])
    assert np.all(robot.upper_rad == launch["UPPER_RAD"])

    urdf = ET.fromstring(launch["snake_urdf"]())
    assert [j.get("name") for j in urdf.findall("joint")] == names
    assert {j.find("axis").get("xyz") for j in urdf.findall("joint")} == {"0 0 1"}  # type: ignore[union-attr]
    control = urdf.find("ros2_control")
    assert control is not None
    params = hardware_params(control)
    namespace = launch["NAMESPACE"]
    assert params["joint_states_topic"] == f"{namespace}/joint_states"
    assert params["joint_commands_topic"] == f"{namespace}/joint_commands"
    assert [j.get("name") for j in control.findall("joint")] == names

    description = launch["generate_launch_description"]()
    actions = description.args[0]
    command = actions[0].kwargs["cmd"]
    assert command[:2] == ["snakebot", "ros2"] and f"__ns:={namespace}" in command
    spawned = [a.kwargs["arguments"] for a in actions if a.kwargs.get("executable") == "spawner"]
    assert [s[0] for s in spawned] == ["joint_state_broadcaster", "forward_position_controller"]
    assert all(s[1:] == ["--param-file", launch["CONTROLLERS"]] for s in spawned)

    controllers = yaml.safe_load(block("yaml"))
    assert controllers["controller_manager"]["ros__parameters"]["update_rate"] == DEFAULT_RATE_HZ
    forward = controllers["forward_position_controller"]["ros__parameters"]
    assert forward["joints"] == names and forward["interface_name"] == "position"
    assert (tmp_path / "snake_controllers.yaml").name == Path(launch["CONTROLLERS"]).name


def test_the_reading_snippet_runs_on_a_recording(tmp_path: Path) -> None:
    pytest.importorskip("mcap_ros2")
    from snakebot.control.cycle import CycleRecord
    from snakebot.telemetry.ros2_mcap import Ros2McapRecorder
    from snakebot.types import JointState

    with Ros2McapRecorder(
        tmp_path / "run.mcap", joint_names=["joint0"], servo_ids=[1], rate_hz=100.0
    ) as recorder:
        for cycle in (1, 2):
            q = np.array([0.25 * cycle])
            state = JointState(0.01 * cycle, q, q, q)
            recorder(CycleRecord(cycle, 0.0, q, q, state, None, 1.0, True, 0.01, False, 100.0))
    result = subprocess.run(
        [sys.executable, "-c", block("python", 1)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    assert [line.split()[1:] for line in result.stdout.splitlines()] == [
        ["joint0", "0.25"],
        ["joint0", "0.5"],
    ]
