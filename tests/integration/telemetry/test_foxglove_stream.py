"""`--foxglove`: a client speaking foxglove.websocket.v1 receives the joint and scene channels."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("foxglove")
pytest.importorskip("websockets")

from snakebot.config import load_robot
from tests.integration.telemetry.foxglove_client import FoxgloveClient


def test_a_client_receives_the_joint_and_scene_channels_from_a_run() -> None:
    robot = load_robot("snake8")
    started = time.monotonic()
    proc = subprocess.Popen(
        [sys.executable, "-m", "snakebot", "run", "--duration", "6", "--foxglove=0", "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stderr is not None
        line = proc.stderr.readline()
        match = re.search(r"ws://127\.0\.0\.1:(\d+)", line)
        assert match, line
        client = FoxgloveClient(match.group(0))
        topics = ["/joints", "/tf", "/scene", "/run_metrics"]
        client.read_advertisements(set(topics))
        client.subscribe(topics)
        client.collect({"/joints": 40, "/tf": 5, "/scene": 1, "/run_metrics": 2})
        client.close()
        stdout, stderr = proc.communicate(timeout=60)
        wall_s = time.monotonic() - started
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 0, stderr
    assert json.loads(stdout)["foxglove"] == match.group(0)

    joints = client.channels["/joints"]
    assert (joints["encoding"], joints["schemaName"]) == ("json", "snakebot.Joints")
    assert "position_rad" in json.loads(joints["schema"])["properties"]
    assert client.channels["/tf"]["schemaName"] == "foxglove.FrameTransforms"
    assert client.channels["/scene"]["schemaName"] == "foxglove.SceneUpdate"

    messages = [m for _, m in client.messages["/joints"]]
    cycles = [m["cycle"] for m in messages]
    assert cycles == list(range(cycles[0], cycles[0] + len(cycles)))  # none dropped, in order
    for message in messages:
        for key in ("command_rad", "position_rad", "velocity_rad_s", "effort_nm"):
            assert len(message[key]) == robot.joint_count
        assert np.allclose(
            np.subtract(message["command_rad"], message["position_rad"]),
            message["tracking_error_rad"],
            atol=2e-6,
        )
    assert max(abs(v) for m in messages for v in m["command_rad"]) > 0.05  # the gait moves
    times = [t for t, _ in client.messages["/joints"]]
    assert np.allclose(np.diff(times), 10_000_000, atol=1_000)  # 100 Hz robot time, in ns
    # Watched, the twin keeps to the wall clock without --realtime: 6 s and the 1 s ramp-out.
    assert wall_s >= 7.0

    transforms = client.messages["/tf"][-1][1]["transforms"]
    assert [t["child_frame_id"] for t in transforms] == [f"link{i}" for i in range(9)]
    origins = np.array([[t["translation"][a] for a in "xyz"] for t in transforms])
    spacing = np.linalg.norm(np.diff(origins, axis=0), axis=1)
    assert np.allclose(spacing, robot.link.length_m, atol=1e-4)  # the links hang together
    scene = client.messages["/scene"][0][1]
    assert [e["frame_id"] for e in scene["entities"]] == [f"link{i}" for i in range(9)]
    assert all(e["frame_locked"] and e["cylinders"] for e in scene["entities"])
    metrics = client.messages["/run_metrics"][-1][1]
    assert metrics["rate_hz"] == 100.0 and metrics["cycles"] > 0


def test_a_port_in_use_is_exit_1_naming_the_option_before_the_run_starts() -> None:
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = subprocess.run(
            [sys.executable, "-m", "snakebot", "run", "--duration", "1", f"--foxglove={port}"],
            capture_output=True,
            text=True,
            timeout=60,
        )
    assert result.returncode == 1, result.stderr
    assert "--foxglove" in result.stderr and str(port) in result.stderr
    assert "Traceback" not in result.stderr


def test_a_scripted_drive_streams_its_status_and_joints(tmp_path: Path) -> None:
    script = tmp_path / "tour.txt"
    script.write_text("0.0 w\n0.0 w\n1.0 a\n4.0 q\n")
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "snakebot",
            "drive",
            "--script",
            str(script),
            "--foxglove=0",
            "--json",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stderr is not None
        match = re.search(r"ws://127\.0\.0\.1:(\d+)", proc.stderr.readline())
        assert match
        client = FoxgloveClient(match.group(0))
        topics = ["/joints", "/drive", "/tf"]
        client.read_advertisements(set(topics))
        client.subscribe(topics)
        client.collect({"/joints": 50, "/drive": 50, "/tf": 5})
        client.close()
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 0, stderr
    assert json.loads(stdout)["stopped_by"] == "quit"
    drive = [m for _, m in client.messages["/drive"]]
    assert {m["gait"] for m in drive} == {"serpenoid"}
    assert all(len(m["target_rad"]) == 8 for m in drive)
    assert max(m["speed"] for m in drive) > 0.0  # the keys took effect on the stream


@pytest.mark.parametrize(("host", "loopback"), [("0.0.0.0", "127.0.0.1"), ("::", r"\[::1\]")])
def test_a_wildcard_host_warns_and_prints_a_url_that_works(host: str, loopback: str) -> None:
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "snakebot",
            "run",
            "--duration",
            "1",
            "--foxglove=0",
            "--foxglove-host",
            host,
            "--json",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stderr is not None
        line = proc.stderr.readline()
        match = re.search(rf"ws://{loopback}:(\d+)", line)
        assert match, line
        warning = proc.stderr.readline()
        assert "reachable from the network" in warning
        client = FoxgloveClient(match.group(0))  # the printed URL is one a client can open
        client.read_advertisements({"/joints"})
        client.close()
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 0, stderr
    summary = json.loads(stdout)
    assert summary["foxglove"] == match.group(0)
    assert summary["foxglove_clients"]["accepted"] == 1
