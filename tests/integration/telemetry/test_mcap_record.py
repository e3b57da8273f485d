"""`--mcap FILE`: the Foxglove channels recorded, read back with the mcap reader, every cycle."""

from __future__ import annotations

import json
import subprocess
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("foxglove")
pytest.importorskip("mcap")

from mcap.reader import make_reader

from snakebot.telemetry import read_log
from snakebot.telemetry.sidecar import read_sidecar

DRIVE_SCRIPT = Path(__file__).parents[1] / "drive" / "snake8_forward_left.txt"


def read_mcap(path: Path) -> tuple[dict[str, list[tuple[int, Any]]], dict[str, str]]:
    """Topic -> [(log_time ns, decoded JSON)], and topic -> schema name."""
    topics: dict[str, list[tuple[int, Any]]] = defaultdict(list)
    schema_names: dict[str, str] = {}
    with path.open("rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages(log_time_order=True):
            assert channel.message_encoding == "json"
            schema_names[channel.topic] = schema.name if schema else ""
            topics[channel.topic].append((message.log_time, json.loads(message.data)))
    return topics, schema_names


def snakebot(*argv: str) -> dict[str, Any]:
    result = subprocess.run(
        [sys.executable, "-m", "snakebot", *argv, "--json"],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert result.returncode == 0, result.stderr
    summary: dict[str, Any] = json.loads(result.stdout)
    return summary


def test_a_run_records_every_cycle_and_the_scene(tmp_path: Path) -> None:
    csv, mcap = tmp_path / "run.csv", tmp_path / "run.mcap"
    summary = snakebot("run", "--duration", "3", "--log", str(csv), "--mcap", str(mcap))
    assert summary["mcap"] == str(mcap)
    topics, schema_names = read_mcap(mcap)
    log = read_log(csv)

    joints = [m for _, m in topics["/joints"]]
    assert len(joints) == len(log.values) == summary["control_cycles"] + 100  # + 1 s ramp-out
    assert [m["cycle"] for m in joints] == log.column("cycle").astype(int).tolist()
    for key, prefix in (
        ("command_rad", "command_rad"),
        ("position_rad", "position_rad"),
        ("effort_nm", "effort_nm"),
    ):
        recorded = np.array([m[key] for m in joints])
        assert np.allclose(recorded, log.joints(prefix), atol=1e-5, rtol=1e-5), key
    com = np.array([m["com_m"] for m in joints])
    assert np.allclose(com[:, 0], log.column("com_x_m"), atol=1e-5)

    assert schema_names["/joints"] == "snakebot.Joints"
    assert schema_names["/tf"] == "foxglove.FrameTransforms"
    assert schema_names["/scene"] == "foxglove.SceneUpdate"
    assert 119 <= len(topics["/tf"]) <= 121  # 30 Hz (as documented) over 4 s of robot time
    assert 15 <= len(topics["/run_metrics"]) <= 17  # 4 Hz
    times = np.array([t for t, _ in topics["/joints"]])
    assert np.allclose(np.diff(times), 1e7, atol=1e3)  # robot time, 100 Hz
    tf_last = topics["/tf"][-1][1]["transforms"]
    head = tf_last[0]["translation"]
    # The twin moved: the head's frame is where its last CoM row says the body went, roughly.
    assert abs(head["x"] - log.column("com_x_m")[-1]) < 0.4
    assert topics["/run_metrics"][-1][1]["cycles"] > 300


def test_a_scripted_drive_records_the_drive_status(tmp_path: Path) -> None:
    csv, mcap = tmp_path / "drive.csv", tmp_path / "drive.mcap"
    summary = snakebot(
        "drive", "--script", str(DRIVE_SCRIPT), "--log", str(csv), "--mcap", str(mcap)
    )
    topics, schema_names = read_mcap(mcap)
    log = read_log(csv)
    assert len(topics["/joints"]) == len(log.values) == summary["control_cycles"]
    # A drive's cycles count from 0 as a run's do (the sidecar says so), in the CSV and MCAP.
    cycles = log.column("cycle").astype(int).tolist()
    assert cycles == list(range(len(cycles)))
    assert [m["cycle"] for _, m in topics["/joints"]] == cycles
    sidecar = read_sidecar(csv)
    assert sidecar is not None
    described = {c["name"]: c["description"] for c in sidecar["columns"]}
    assert described["cycle"] == "control cycle number, from 0"
    assert "backend_stats" in summary  # the drive's summary has every key of a run's
    drive = [m for _, m in topics["/drive"]]
    assert len(drive) == len(topics["/joints"])
    assert schema_names["/drive"] == "snakebot.DriveStatus"
    keys = [k for m in drive for k in m["keys"]]
    assert keys == ["w", "w", "w", "w", "a", "a", "q"]
    assert max(m["speed"] for m in drive) == pytest.approx(1.0)
    assert max(m["turn"] for m in drive) == pytest.approx(0.5)
    assert {m["gait"] for m in drive} == {"serpenoid"}


def test_a_killed_run_keeps_all_but_the_last_second_of_its_mcap(tmp_path: Path) -> None:
    """The chunk is closed every second: kill -9 loses at most that (the CSV loses nothing)."""
    import signal
    import time

    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader

    csv, mcap = tmp_path / "run.csv", tmp_path / "run.mcap"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "snakebot",
            "run",
            "--duration",
            "30",
            "--realtime",
            "--log",
            str(csv),
            "--mcap",
            str(mcap),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline and (not csv.exists() or len(read_log(csv).values) < 350):
        time.sleep(0.2)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    rows = len(read_log(csv).values)
    assert rows >= 350
    cycles, topics = [], {}
    try:
        for record in StreamReader(str(mcap)).records:
            if isinstance(record, Channel):
                topics[record.id] = record.topic
            elif isinstance(record, Message) and topics.get(record.channel_id) == "/joints":
                cycles.append(json.loads(record.data)["cycle"])
    except Exception:  # the torn end of the unfinished file
        pass
    assert cycles == list(range(len(cycles)))
    assert len(cycles) >= rows - 100 - 50  # a second at 100 Hz, and the CSV went on meanwhile
