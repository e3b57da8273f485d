"""``snakebot log export``: a telemetry CSV as MCAP (the live channels, for Foxglove) or Parquet.

MCAP goes through the same :class:`~snakebot.telemetry.foxglove_live.FoxgloveTelemetry` as a
live ``--mcap`` recording (with ``ros2``, the same
:class:`~snakebot.telemetry.ros2_mcap.Ros2McapRecorder` as ``--mcap-encoding ros2``), timed at
the sidecar's start time plus robot time; the 3-D scene is
the forward kinematics of the logged joint angles through the twin's model of the sidecar's
robot (when that robot file is still there). Parquet needs pyarrow (``snakebot[parquet]``):
the columns as float64, the sidecar in the file's key-value metadata under ``snakebot``.
"""

from __future__ import annotations

import datetime
import json
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from snakebot.control.cycle import CycleRecord
from snakebot.errors import ConfigError, MissingDependencyError, OutputError
from snakebot.telemetry.csv_log import TelemetryLog
from snakebot.telemetry.foxglove_live import FoxgloveTelemetry, Geometry, TelemetryOptions
from snakebot.telemetry.log_summary import com_path, nominal_period_s
from snakebot.types import BodyState, JointState

FORMATS = ("mcap", "parquet")
PARQUET_INSTALL = "pip install 'snakebot[parquet]'"


def export_mcap(log: TelemetryLog, sidecar: dict[str, Any] | None, path: Path) -> int:
    """Write ``log`` to MCAP at ``path``; returns the cycles written."""
    meta = sidecar or {}
    period = nominal_period_s(log, sidecar)
    robot = meta.get("robot", {})
    servo_ids = robot.get("servo_ids") or list(range(log.joints("command_rad").shape[1]))
    sink = FoxgloveTelemetry(
        TelemetryOptions(mcap_path=path),
        servo_ids=servo_ids,
        rate_hz=1.0 / period if period else 0.0,
        geometry=_geometry(meta),
        start_epoch_ns=_start_ns(meta),
    )
    with sink:
        for record in log_records(log):
            sink(record)
    return sink.rows


def export_ros2_mcap(log: TelemetryLog, sidecar: dict[str, Any] | None, path: Path) -> int:
    """Write ``log`` to MCAP at ``path`` as standard ROS 2 messages in CDR; returns the cycles
    written (MissingDependencyError without the mcap package)."""
    from snakebot.telemetry.ros2_mcap import Ros2McapRecorder

    meta = sidecar or {}
    period = nominal_period_s(log, sidecar)
    robot = meta.get("robot", {})
    joints = log.joints("command_rad").shape[1]
    names = [f"joint{i}" for i in range(joints)]  # the twin's and snakebot ros2's names
    recorder = Ros2McapRecorder(
        path,
        joint_names=names,
        servo_ids=robot.get("servo_ids") or list(range(joints)),
        rate_hz=1.0 / period if period else 0.0,
        geometry=_geometry(meta),
        robot_name=str(robot.get("name", "")),
        metadata={"exported_from": json.dumps(meta, default=str)},
        start_epoch_ns=_start_ns(meta),
    )
    with recorder:
        for record in log_records(log):
            recorder(record)
    return recorder.rows


def log_records(log: TelemetryLog) -> Iterator[CycleRecord]:
    """The cycles of a log as the records the loop made, as far as the log holds them: the
    logged cycle, time, command and measured state, and the COM (when logged) with the head's
    orientation (NaN where not logged). A log does not hold the gait's target (the command
    stands in), the amplitude (NaN), whether the cycle was scored (True) or late (False)."""
    time_s, cycle = log.column("time_s"), log.column("cycle").astype(int)
    command, position = log.joints("command_rad"), log.joints("position_rad")
    velocity, effort = log.joints("velocity_rad_s"), log.joints("effort_nm")
    com = com_path(log)
    quat = np.column_stack(
        [
            log.column(name) if name in log.columns else np.full(len(time_s), np.nan)
            for name in ("imu_qw", "imu_qx", "imu_qy", "imu_qz")
        ]
    )
    start = float(time_s[0]) if len(time_s) else 0.0
    for row in range(len(time_s)):
        now = float(time_s[row])
        yield CycleRecord(
            cycle=int(cycle[row]) + 1,
            gait_time_s=now - start,
            target_rad=command[row],
            command_rad=command[row],
            state=JointState(now, position[row], velocity[row], effort[row]),
            body=None if com is None else BodyState(com[row], quat[row]),
            amplitude=math.nan,
            scored=True,
            period_s=now - float(time_s[row - 1]) if row else 0.0,
            overrun=False,
            achieved_rate_hz=row / (now - start) if now > start else 0.0,
        )


def export_parquet(log: TelemetryLog, sidecar: dict[str, Any] | None, path: Path) -> int:
    """Write ``log`` to Parquet at ``path``; returns the rows written."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError as exc:
        raise MissingDependencyError(
            f"Parquet export needs pyarrow: {PARQUET_INSTALL} (or export to MCAP)"
        ) from exc
    columns = {
        name: pa.array(np.ascontiguousarray(log.values[:, i])) for i, name in enumerate(log.columns)
    }
    table = pa.table(columns)
    if sidecar:
        table = table.replace_schema_metadata({"snakebot": json.dumps(sidecar)})
    try:
        pq.write_table(table, path)
    except OSError as exc:
        raise OutputError(path, f"cannot write the Parquet file: {exc}") from exc
    return int(table.num_rows)


def _geometry(meta: dict[str, Any]) -> Geometry | None:
    """The scene of the sidecar's robot, from its robot file; None when it cannot be loaded."""
    source = meta.get("robot", {}).get("source")
    if not source or not Path(source).is_file():
        return None
    from snakebot.config import load_robot
    from snakebot.telemetry.scene import KinematicLinkPoses

    try:
        robot = load_robot(source)
    except ConfigError:
        return None
    poses = KinematicLinkPoses(robot)
    return Geometry(robot.link_count, robot.link.length_m, robot.link.radius_m, lambda: poses)


def _start_ns(meta: dict[str, Any]) -> int:
    created = meta.get("created_utc")
    if isinstance(created, str):
        try:
            return int(datetime.datetime.fromisoformat(created).timestamp() * 1e9)
        except ValueError:
            pass
    return 0
