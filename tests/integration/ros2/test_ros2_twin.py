"""`snakebot ros2 --robot snake12 --backend twin` driven by a second node over real rclpy.

cmd_vel for 5 s moves and turns the snake, joint_states arrive at the control rate (counted
against the cycles the stamps say were run, not the wall clock: a loaded machine runs late),
the gait parameter selects a gait and refuses what cannot be driven, SIGTERM ends the node
in the stop policy, and when cmd_vel stops the command
timeout ends the node at the rest pose in the stop policy.
"""

from __future__ import annotations

import math
import signal
import time

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="needs the ros2 extra: pip install 'snakebot[ros2]'")

from tests.integration.ros2.rosclient import STARTUP_S, client, ros2_node

pytestmark = pytest.mark.slow

RATE_HZ = 100.0
DRIVE_S = 5.0


def test_cmd_vel_moves_and_turns_the_twin_and_a_stale_stream_ends_in_the_stop_policy() -> None:
    with (
        client() as ros,
        ros2_node("--robot", "snake12", "--backend", "twin", "--command-timeout", "1") as node,
    ):
        ros.wait_for(
            lambda: len(ros.joint_states()) > 10 or not node.running(), STARTUP_S, "joint_states"
        )
        assert node.running(), node.finish()
        start = len(ros.joint_states())
        began = time.monotonic()
        while time.monotonic() - began < DRIVE_S:
            ros.steer(0.5, 0.4)  # half speed, turning left
            time.sleep(0.05)
        driven = ros.joint_states()[start:]
        # No more cmd_vel: after the 1 s timeout the node blends to rest and exits.
        summary = node.finish(timeout_s=90.0)
    assert node.proc.returncode == 1, node.err
    assert "no command for 1 s; the snake was stopped (hold at the rest pose)" in node.err
    assert summary["stopped_by"] == "no command for 1 s" and summary["command_timeouts"] == 1
    assert summary["commands"] >= 20 and summary["refused_commands"] == 0

    stamps = np.array([stamp for stamp, _, _ in driven])
    cycles = round((stamps[-1] - stamps[0]) * RATE_HZ) + 1
    assert len(np.unique(stamps)) >= 0.9 * cycles, (len(stamps), cycles)
    assert np.all(np.diff(stamps) > 0)  # stamped with each cycle's time, in order
    # Most of the 5 s of wall time became cycles (a loaded machine runs somewhat late).
    assert cycles >= 0.5 * DRIVE_S * RATE_HZ

    assert summary["distance_m"] > 0.3
    assert summary["turn_deg"] > 45  # counter-clockwise seen from above: left
    poses = np.array([pose for _, pose in ros.heard.body_pose])
    assert np.linalg.norm(poses[-1, :2] - poses[0, :2]) > 0.3  # the tf the node published
    # It ended on its way to the rest pose (straight): the last command was exactly that, the
    # joints track it a few cycles behind (backend.close then holds it).
    last = ros.joint_states()[-1][1]
    assert np.abs(np.array([p for _, p, _ in driven])).max() > 0.5
    assert np.abs(last).max() < 0.2
    names = {status.name for array in ros.heard.diagnostics for status in array.status}
    assert "snakebot: joint0" in names and "snakebot: run" in names


def test_the_gait_parameter_selects_by_name_and_refuses_what_cannot_be_driven() -> None:
    from rcl_interfaces.srv import GetParameters, SetParameters
    from rclpy.parameter import Parameter

    started = ("--command-timeout", "0", "--ros-args", "-p", "gait:=rolling")
    with client() as ros, ros2_node("--robot", "snake12", *started) as node:
        ros.wait_for(
            lambda: len(ros.joint_states()) > 5 or not node.running(), STARTUP_S, "joint_states"
        )
        service = ros.node.create_client(SetParameters, "/snakebot/set_parameters")
        getter = ros.node.create_client(GetParameters, "/snakebot/get_parameters")
        assert service.wait_for_service(timeout_sec=30.0)
        assert getter.wait_for_service(timeout_sec=30.0)

        def set_gait(name: str, params: str) -> tuple[bool, str]:
            request = SetParameters.Request(
                parameters=[
                    Parameter("gait", value=name).to_parameter_msg(),
                    Parameter("gait_params", value=params).to_parameter_msg(),
                ]
            )
            future = service.call_async(request)
            ros.wait_for(future.done, 30.0, "the parameter service")
            results = future.result().results
            return all(r.successful for r in results), " ".join(r.reason for r in results)

        asked = GetParameters.Request(names=["gait", "gait_params"])
        future = getter.call_async(asked)
        ros.wait_for(future.done, 30.0, "the parameter service")
        assert [v.string_value for v in future.result().values] == ["rolling", ""]
        ok, reason = set_gait("lateral_undulation", "")
        assert ok, reason
        ok, reason = set_gait("rolling", "")
        assert ok, reason
        ok, reason = set_gait("moonwalk", "")
        assert not ok and "moonwalk" in reason
        ok, reason = set_gait("sidewinding", "bogus=1")
        assert not ok and "bogus" in reason
        before = ros.joint_states()[-1][1]
        for _ in range(60):  # 3 s of rolling
            ros.steer(0.5, 0.0)
            time.sleep(0.05)
        moved = ros.joint_states()[-1][1]
        node.interrupt(signal.SIGTERM)  # as `ros2 launch` and systemd stop a node
        summary = node.finish()
    assert node.proc.returncode == 130, node.err
    assert summary["stopped_by"] == "interrupted (SIGTERM)"
    assert np.abs(moved - before).max() > 0.2  # the rolling gait played
    assert math.isfinite(summary["distance_m"])
