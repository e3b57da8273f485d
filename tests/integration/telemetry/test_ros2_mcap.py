"""`--mcap FILE --mcap-encoding ros2`: standard ROS 2 messages in CDR, read back by two readers.

rosbags decodes with the definitions of a ROS 2 Kilted installation (its own type store, not the
text snakebot wrote), mcap-ros2-support with the definitions in the file: both must agree with
the CSV log of the same run.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("mcap_ros2")
pytest.importorskip("rosbags")

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from snakebot.config import load_robot
from snakebot.control.cycle import CycleRecord
from snakebot.telemetry import read_log
from snakebot.telemetry.ros2_mcap import Ros2McapRecorder, Ros2Readings
from snakebot.types import JointState

TYPES = {
    "/joint_states": "sensor_msgs/msg/JointState",
    "/snakebot/joint_commands_sent": "sensor_msgs/msg/JointState",
    "/body_pose": "geometry_msgs/msg/TransformStamped",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
    "/run_metrics": "diagnostic_msgs/msg/DiagnosticStatus",
}


def stamp_ns(message: Any) -> int:
    return int(message.header.stamp.sec) * 1_000_000_000 + int(message.header.stamp.nanosec)


def read_rosbags(path: Path) -> dict[str, list[tuple[int, Any]]]:
    """Topic -> [(log time ns, message)], decoded with ROS 2 Kilted's own definitions."""
    kilted = get_typestore(Stores.ROS2_KILTED)
    topics: dict[str, list[tuple[int, Any]]] = defaultdict(list)
    with AnyReader([path]) as reader:
        assert {c.topic: c.msgtype for c in reader.connections} == TYPES
        for connection, log_time, raw in reader.messages():
            assert connection.msgtype is not None
            message = kilted.deserialize_cdr(raw, connection.msgtype)
            topics[connection.topic].append((log_time, message))
    return topics


def read_mcap_ros2(path: Path) -> dict[str, list[Any]]:
    """Topic -> [message], decoded by mcap-ros2-support from the definitions in the file."""
    topics: dict[str, list[Any]] = defaultdict(list)
    with path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        for schema, channel, _, message in reader.iter_decoded_messages():
            assert schema is not None and schema.encoding == "ros2msg"
            assert channel.message_encoding == "cdr"
            assert schema.name == TYPES[channel.topic]
            topics[channel.topic].append(message)
    return topics


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


def test_a_twin_run_opens_in_rosbags_and_mcap_ros2_with_the_standard_types(
    tmp_path: Path,
) -> None:
    csv, mcap = tmp_path / "run.csv", tmp_path / "run.mcap"
    summary = snakebot(
        "run", "--duration", "2", "--log", str(csv), "--mcap", str(mcap), "--mcap-encoding", "ros2"
    )
    assert summary["mcap"] == str(mcap)
    log = read_log(csv)
    joints = summary["joints"]
    names = [f"joint{i}" for i in range(joints)]
    topics = read_rosbags(mcap)
    decoded = read_mcap_ros2(mcap)

    states = [m for _, m in topics["/joint_states"]]
    assert len(states) == len(log.values) == summary["control_cycles"] + 100  # + 1 s ramp-out
    assert all(m.name == names for m in states)
    position = np.array([m.position for m in states])
    # The CSV keeps 6 significant digits; the CDR file the float64 itself.
    close = {"rtol": 1e-5, "atol": 1e-12}
    assert np.allclose(position, log.joints("position_rad"), **close)
    assert np.allclose([m.velocity for m in states], log.joints("velocity_rad_s"), **close)
    assert np.allclose([m.effort for m in states], log.joints("effort_nm"), **close)
    sent = [m for _, m in topics["/snakebot/joint_commands_sent"]]
    assert np.allclose([m.position for m in sent], log.joints("command_rad"), **close)
    assert all(len(m.velocity) == len(m.effort) == 0 for m in sent)
    # The second reader sees the same numbers.
    assert [list(m.name) for m in decoded["/joint_states"]] == [names] * len(states)
    assert np.array_equal([m.position for m in decoded["/joint_states"]], position)

    # Stamps: the start's wall clock plus robot time, equal to the log time, rising 10 ms a cycle.
    stamps = np.array([stamp_ns(m) for m in states])
    assert np.array_equal(stamps, [t for t, _ in topics["/joint_states"]])
    assert np.all(np.diff(stamps) > 0)
    assert np.allclose(np.diff(stamps), 1e7, atol=1e3)
    assert np.allclose((stamps - stamps[0]) / 1e9, log.column("time_s") - log.column("time_s")[0])
    assert abs(stamps[0] / 1e9 - time.time()) < 600

    tf = [m for _, m in topics["/tf"]]
    assert 89 <= len(tf) <= 91  # 30 Hz over 3 s of robot time
    frames = [f"link{i}" for i in range(joints + 1)]
    assert all([t.child_frame_id for t in m.transforms] == frames for m in tf)
    assert all(t.header.frame_id == "world" for m in tf for t in m.transforms)
    assert np.all(np.diff([stamp_ns(m.transforms[0]) for m in tf]) > 0)
    last = tf[-1].transforms
    quats = np.array([[t.transform.rotation.x, t.transform.rotation.w] for t in last])
    assert np.all(np.abs(quats) <= 1.0 + 1e-9)
    head = last[0].transform.translation
    assert abs(head.x - log.column("com_x_m")[-1]) < 0.4  # the head went where the body went
    assert head.x > 0.1  # and the body moved

    # The body pose every cycle: the centre of mass, as in the CSV, the head's orientation.
    poses = [m for _, m in topics["/body_pose"]]
    assert len(poses) == len(states)
    assert {(m.header.frame_id, m.child_frame_id) for m in poses} == {("world", "snakebot_body")}
    assert [stamp_ns(m) for m in poses] == stamps.tolist()
    com = np.array([[m.transform.translation.x, m.transform.translation.y] for m in poses])
    assert np.allclose(com, np.c_[log.column("com_x_m"), log.column("com_y_m")], **close)
    rotation = poses[-1].transform.rotation
    quat = [rotation.w, rotation.x, rotation.y, rotation.z]
    assert np.allclose(quat, [log.column(f"imu_q{a}")[-1] for a in "wxyz"], **close)

    diagnostics = [m for _, m in topics["/diagnostics"]]
    assert len(diagnostics) == 3  # 1 Hz over 3 s of robot time
    for message in diagnostics:  # a status per servo, then the run's
        assert [s.name for s in message.status] == [f"snakebot: {n}" for n in names] + [
            "snakebot: run"
        ]
        servos = [s.hardware_id for s in message.status[:-1]]
        assert servos == [f"servo {i}" for i in load_robot(summary["robot"]).servo_ids]
    run = [m for _, m in topics["/run_metrics"]]
    assert [m.name for m in run] == ["snakebot: run"] * 3
    assert {m.hardware_id for m in run} == {summary["robot"]}
    assert [[(kv.key, kv.value) for kv in m.values] for m in run] == [
        [(kv.key, kv.value) for kv in d.status[-1].values] for d in diagnostics
    ]
    values = [{kv.key: kv.value for kv in m.values} for m in run]
    assert {v["rate_hz"] for v in values} == {"100"}
    cycles = [int(v["cycles"]) for v in values]
    assert cycles == sorted(cycles) and cycles[-1] >= 200
    assert float(values[-1]["achieved_rate_hz"]) == pytest.approx(100.0, rel=1e-3)
    assert float(values[-1]["distance_m"]) > 0.1

    # The CSV log rebuilds the same file (a killed run's MCAP loses its last second, the CSV
    # nothing): the same topics and types, every row, its numbers.
    exported = tmp_path / "run.export.mcap"
    snakebot("log", "export", str(csv), "--format", "mcap", "--mcap-encoding", "ros2")
    again = read_rosbags(exported)
    assert len(again["/joint_states"]) == len(states)
    assert np.array_equal(
        [m.position for _, m in again["/joint_states"]], log.joints("position_rad")
    )
    assert np.all(np.diff([t for t, _ in again["/joint_states"]]) > 0)
    assert [m.name for _, m in again["/run_metrics"]] == ["snakebot: run"] * 3


def _record(cycle: int, time_s: float, joints: int) -> CycleRecord:
    q = np.full(joints, 0.1 * cycle)
    state = JointState(time_s, q, np.zeros(joints), np.zeros(joints))
    return CycleRecord(cycle, time_s, q, q + 0.01, state, None, 1.0, True, 0.01, False, 100.0)


def test_servo_health_and_hardware_errors_become_diagnostic_statuses(tmp_path: Path) -> None:
    path = tmp_path / "bus.mcap"
    readings = Ros2Readings(
        health=lambda: {"temperature_c": np.array([31.0, 45.5]), "input_voltage_v": np.full(2, 12)},
        faults=lambda: {7: ["overheating", "overload"]},
        alerts=lambda: ["alert bit: servo 7"],
        overruns=lambda: 3,
    )
    with Ros2McapRecorder(
        path,
        joint_names=["joint0", "joint1"],
        servo_ids=[3, 7],
        rate_hz=100.0,
        readings=readings,
        status_rate_hz=4.0,
    ) as recorder:
        for cycle in range(1, 31):
            recorder(_record(cycle, 0.01 * cycle, 2))
    assert recorder.rows == 30
    topics = read_rosbags_any(path)
    # No body (hardware): no /body_pose; no geometry given: no /tf.
    assert set(topics) == {
        "/joint_states",
        "/snakebot/joint_commands_sent",
        "/diagnostics",
        "/run_metrics",
    }
    assert len(topics["/joint_states"]) == 30
    statuses = {s.name: s for s in topics["/diagnostics"][-1].status}
    assert set(statuses) == {"snakebot: run", "snakebot: joint0", "snakebot: joint1"}
    head, second = statuses["snakebot: joint0"], statuses["snakebot: joint1"]
    assert (head.level, head.hardware_id, head.message) == (0, "servo 3", "OK")
    assert (second.level, second.hardware_id) == (2, "servo 7")  # ERROR
    assert second.message == "overheating, overload"
    values = {kv.key: kv.value for kv in second.values}
    assert values["temperature_c"] == "45.5"
    assert values["input_voltage_v"] == "12"
    assert values["servo_id"] == "7"
    run = statuses["snakebot: run"]
    assert run.level == 1 and run.message == "alert bit: servo 7"  # WARN
    assert {kv.key: kv.value for kv in run.values}["overruns"] == "3"


def read_rosbags_any(path: Path) -> dict[str, list[Any]]:
    """Topic -> [message] by rosbags with the definitions in the file (no /tf needed)."""
    topics: dict[str, list[Any]] = defaultdict(list)
    with AnyReader([path]) as reader:
        for connection, _, raw in reader.messages():
            topics[connection.topic].append(reader.deserialize(raw, connection.msgtype))
    return topics


def test_a_stopped_run_finishes_the_file_and_a_killed_one_keeps_all_but_a_second(
    tmp_path: Path,
) -> None:
    """SIGTERM ends the run in its ramp-out and a finished file; SIGKILL loses at most the
    chunk of the last second (the CSV loses nothing)."""
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader

    for sig in (signal.SIGTERM, signal.SIGKILL):
        csv, mcap = tmp_path / f"{sig.name}.csv", tmp_path / f"{sig.name}.mcap"
        argv = ["run", "--duration", "30", "--realtime", "--log", str(csv), "--mcap", str(mcap)]
        proc = subprocess.Popen(
            [sys.executable, "-m", "snakebot", *argv, "--mcap-encoding", "ros2"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline and (not csv.exists() or len(read_log(csv).values) < 250):
            time.sleep(0.2)
        proc.send_signal(sig)
        proc.wait(timeout=60)
        rows = len(read_log(csv).values)
        assert rows >= 250
        if sig == signal.SIGTERM:
            assert proc.returncode == 130
            with mcap.open("rb") as stream:
                summary = make_reader(stream).get_summary()
            assert summary is not None and summary.statistics is not None
            counts = summary.statistics.channel_message_counts
            assert rows in counts.values()  # every cycle's joint states, the ramp-out's too
            assert len(read_rosbags(mcap)["/joint_states"]) == rows
            continue
        names: dict[int, str] = {}
        stamps: list[int] = []
        try:
            for record in StreamReader(str(mcap)).records:
                if isinstance(record, Channel):
                    names[record.id] = record.topic
                elif (
                    isinstance(record, Message) and names.get(record.channel_id) == "/joint_states"
                ):
                    stamps.append(record.log_time)
        except Exception:  # the torn end of the unfinished file
            pass
        assert len(stamps) >= rows - 100 - 50  # a second at 100 Hz, and the CSV went on meanwhile
        assert np.all(np.diff(stamps) > 0)


@pytest.mark.pty
@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX")
def test_a_run_over_the_emulated_bus_records_servo_health_as_diagnostics(tmp_path: Path) -> None:
    from tests.pty_emulator import emulator

    mcap = tmp_path / "bus.mcap"
    with emulator("--robot", "snake8") as emu:
        summary = snakebot(
            "run",
            "--backend",
            "dynamixel",
            "--port",
            emu.port,
            "--robot",
            "snake8",
            "--duration",
            "2",
            "--mcap",
            str(mcap),
            "--mcap-encoding",
            "ros2",
        )
    topics = read_rosbags_any(mcap)
    assert "/body_pose" not in topics  # nothing measures where a real snake is
    # Wall-clock cycles, as many as the bus held, and the ramp-out's after them.
    assert len(topics["/joint_states"]) > summary["control_cycles"] > 50
    assert len(topics["/tf"]) >= 30  # the forward kinematics of the measured joints
    servo_ids = load_robot("snake8").servo_ids
    readings = 0
    for message in topics["/diagnostics"]:
        servos = message.status[:-1]
        assert [s.hardware_id for s in servos] == [f"servo {i}" for i in servo_ids]
        for status in servos:
            values = {kv.key: kv.value for kv in status.values}
            assert values["servo_id"] == status.hardware_id.removeprefix("servo ")
            if "temperature_c" in values:
                readings += 1
                assert 0 < float(values["temperature_c"]) < 80
                assert 5 < float(values["input_voltage_v"]) < 20
                assert (status.level, status.message, values["hardware_errors"]) == (0, "OK", "")
    assert readings >= len(servo_ids)  # every servo's health, once it was read


def test_the_ros2_encoding_goes_with_an_mcap_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from snakebot.cli.main import main

    for argv, message in (
        (["run", "--duration", "1"], "--mcap-encoding ros2 goes with --mcap FILE"),
        (["log", "export", str(tmp_path / "x.csv"), "--format", "parquet"], "--format mcap"),
    ):
        assert main([*argv, "--mcap-encoding", "ros2"]) == 2
        assert message in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs Linux's /dev/full")
def test_a_file_that_cannot_be_written_is_an_output_error_naming_it() -> None:
    from snakebot.errors import OutputError

    with pytest.raises(OutputError, match="/dev/full: cannot write the MCAP file") as caught:
        Ros2McapRecorder(Path("/dev/full"), joint_names=["joint0"], servo_ids=[1], rate_hz=100.0)
    assert "No space left on device" in str(caught.value)
