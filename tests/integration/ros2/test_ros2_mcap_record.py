"""`snakebot ros2 --mcap FILE`: the node records every cycle as ROS 2 messages, the ones its
subscribers hear among them, and Ctrl-C finishes the file."""

from __future__ import annotations

import time
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="needs the ros2 extra: pip install 'snakebot[ros2]'")
pytest.importorskip("rosbags")

from rosbags.highlevel import AnyReader

from tests.integration.ros2.rosclient import STARTUP_S, client, ros2_node

pytestmark = pytest.mark.slow


def test_the_node_records_what_it_publishes(tmp_path: Path) -> None:
    mcap = tmp_path / "node.mcap"
    with (
        client() as ros,
        ros2_node("--robot", "snake8", "--backend", "twin", "--mcap", str(mcap)) as node,
    ):
        ros.wait_for(
            lambda: len(ros.joint_states()) > 10 or not node.running(), STARTUP_S, "joint_states"
        )
        assert node.running(), node.finish()
        began = time.monotonic()
        while time.monotonic() - began < 2.0:
            ros.steer(0.5, 0.0)
            time.sleep(0.05)
        node.interrupt()
        summary = node.finish()
    assert node.proc.returncode == 130, node.err
    assert summary["mcap"] == str(mcap)
    heard = ros.joint_states()

    recorded: dict[str, list[tuple[int, object]]] = {}
    with AnyReader([mcap]) as reader:  # a finished file: rosbags reads its summary
        for connection, log_time, raw in reader.messages():
            message = reader.deserialize(raw, connection.msgtype)
            recorded.setdefault(connection.topic, []).append((log_time, message))
    assert {"/joint_states", "/body_pose", "/tf", "/diagnostics", "/run_metrics"} <= set(recorded)
    states = [m for _, m in recorded["/joint_states"]]
    assert len(states) >= len(heard) > 100  # every cycle, the ramp to rest included
    assert all(list(m.name) == [f"joint{i}" for i in range(8)] for m in states)  # type: ignore[attr-defined]
    times = np.array([t for t, _ in recorded["/joint_states"]])
    assert np.all(np.diff(times) > 0)
    # What the subscriber heard is in the file, cycle for cycle, on the same time line (matched
    # by the positions, where a pose occurs once: a snake standing still repeats its own).
    seen = Counter(m.position.tobytes() for m in states)  # type: ignore[attr-defined]
    by_pose = {m.position.tobytes(): t for t, m in recorded["/joint_states"]}  # type: ignore[attr-defined]
    matched = [(stamp, by_pose[q.tobytes()]) for stamp, q, _ in heard if seen[q.tobytes()] == 1]
    assert len(matched) >= 100  # most of the 2 s driven at 100 Hz
    node_s = np.array([s for s, _ in matched])
    file_s = np.array([t for _, t in matched]) / 1e9
    assert np.allclose(node_s - node_s[0], file_s - file_s[0], atol=1e-6)
    assert summary["distance_m"] > 0.05  # cmd_vel drove it, and the file saw it move
    poses = [m for _, m in recorded["/body_pose"]]
    moved = poses[-1].transform.translation.x - poses[0].transform.translation.x  # type: ignore[attr-defined]
    assert abs(moved) > 0.02
