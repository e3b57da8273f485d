"""A cycle-record sink writing MCAP in the ROS 2 message encoding (CDR) with standard types.

What rosbag2 (``ros2 bag play run.mcap``), Foxglove and rosbags read with no snakebot installed
(docs/ros2.md). The topics are those ``snakebot ros2`` publishes, plus two a node cannot:
``/joint_states`` (sensor_msgs/JointState) every cycle; ``/body_pose``
(geometry_msgs/TransformStamped ``world`` -> ``snakebot_body``) every cycle where the backend
senses the body (the twin); ``/diagnostics`` (diagnostic_msgs/DiagnosticArray: one status per
servo with its health readings and hardware errors where the backend has them, then the run's)
and ``/run_metrics`` (that run status alone) at ``status_rate_hz``; and only in the recording
``/snakebot/joint_commands_sent`` (sensor_msgs/JointState, the positions the safety layer sent)
every cycle and ``/tf`` (tf2_msgs/TFMessage: the twin's simulated link poses, elsewhere the
forward kinematics of the measured joints) at ``tf_rate_hz``. Every message is stamped, and
logged, at the wall clock of the start plus robot time, as the JSON recording is
(:mod:`snakebot.telemetry.foxglove_live`), so stamps rise with the cycles.

The messages are encoded by :mod:`snakebot.telemetry.ros2_msgs` (CDR, with the standard
definitions as ``ros2msg`` schemas) and written by the ``mcap`` package's writer with the
``ros2`` profile: no rclpy, no ROS installation. The open chunk is closed every
:data:`MCAP_FLUSH_S` of robot time: a killed run keeps all but that much, and ``close`` (any end
of the run: an error, Ctrl-C, SIGTERM) finishes the file.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from snakebot.errors import MissingDependencyError, OutputError
from snakebot.telemetry import ros2_msgs
from snakebot.telemetry.run_window import RunWindow, next_due

if TYPE_CHECKING:
    from snakebot.backends.base import Backend
    from snakebot.control.cycle import CycleRecord
    from snakebot.telemetry.foxglove_live import Geometry
    from snakebot.telemetry.scene import LinkPoses

INSTALL = "pip install 'snakebot[ros2-mcap]'"
MCAP_FLUSH_S = 1.0
NODE_NAME = "snakebot"  # the statuses' prefix, as ``snakebot ros2``'s node names them


@dataclass(frozen=True)
class Ros2Readings:
    """The backend's slow readings for ``/diagnostics``: ``health`` (per-servo (N,) arrays by
    name with their unit in it, e.g. ``temperature_c``), ``faults`` (servo ID -> the hardware
    error names it reports now), ``alerts`` (what went wrong so far) and ``overruns``."""

    health: Callable[[], Mapping[str, np.ndarray]] | None = None
    faults: Callable[[], Mapping[int, Sequence[str]]] | None = None
    alerts: Callable[[], Sequence[str]] | None = None
    overruns: Callable[[], int] | None = None


def backend_readings(backend: Backend) -> Ros2Readings:
    """What ``backend`` reports of its servos: the slow readings of a ``ReportsHealth``
    backend plus the current of a ``SensesCurrent`` one, the error bits of the servos raising
    their alert on a servo bus (``OnBus``), the run's alerts and overruns."""
    from snakebot.backends.capabilities import OnBus, SensesCurrent
    from snakebot.drive.observers import backend_readings as display_readings

    slow, alerts = display_readings(backend)

    def health() -> Mapping[str, np.ndarray]:
        readings = dict(slow())
        if isinstance(backend, SensesCurrent):
            readings["current_a"] = backend.present_current_a()
        return readings

    def faults() -> Mapping[int, Sequence[str]]:
        if not isinstance(backend, OnBus):
            return {}
        bus = backend.bus
        found = {}
        for servo in sorted(bus.alerts):
            names = bus.family.status_errors(bus.conditions.get(servo, 0))
            found[servo] = [n for n in names if n != "alert"] or ["alert"]
        return found

    return Ros2Readings(health, faults, alerts, lambda: backend.stats.overruns)


def mcap_writer_module() -> Any:
    """``mcap.writer``, or MissingDependencyError with the install command."""
    try:
        import mcap.writer
    except ImportError as exc:
        raise MissingDependencyError(
            f"MCAP recordings in the ROS 2 encoding need the mcap package: {INSTALL}"
        ) from exc
    return mcap.writer


class Ros2McapRecorder:
    """A :class:`~snakebot.control.cycle.CycleSink` writing each cycle to ``path`` as ROS 2
    messages (see the module docstring for the topics).

    ``joint_names`` (N,) and ``servo_ids`` (N,) are head to tail; ``geometry`` gives ``/tf``
    (None: no ``/tf``); ``robot_name`` is the run status's hardware ID; ``metadata`` goes into
    the file's ``snakebot`` metadata record.
    Opening creates the file: OutputError naming it when it cannot be written,
    MissingDependencyError without the mcap package.
    """

    def __init__(
        self,
        path: Path,
        *,
        joint_names: Sequence[str],
        servo_ids: Sequence[int],
        rate_hz: float,
        geometry: Geometry | None = None,
        readings: Ros2Readings | None = None,
        robot_name: str = "",
        metadata: Mapping[str, str] | None = None,
        tf_rate_hz: float = 30.0,
        status_rate_hz: float = 1.0,
        start_epoch_ns: int | None = None,
    ) -> None:
        if len(joint_names) != len(servo_ids):
            raise ValueError(f"{len(joint_names)} joint names for {len(servo_ids)} servo IDs")
        writer_module = mcap_writer_module()
        self.path = Path(path)
        self.rows = 0
        self.joint_names = tuple(joint_names)
        self.servo_ids = tuple(int(i) for i in servo_ids)
        self.rate_hz = rate_hz
        self.robot_name = robot_name
        self.tf_rate_hz = tf_rate_hz
        self.status_rate_hz = status_rate_hz
        self._geometry = geometry
        self._readings = readings or Ros2Readings()
        self._epoch_ns = time.time_ns() if start_epoch_ns is None else start_epoch_ns
        self._stream: IO[bytes] | None = None
        self._writer: Any = None
        self._channels: dict[str, int] = {}
        self._schemas: dict[str, int] = {}
        with self._failures("cannot write the MCAP file"):
            self._stream = self.path.open("wb")
            compression = writer_module.CompressionType.ZSTD
            self._writer = writer_module.Writer(self._stream, compression=compression)
            self._writer.start(profile="ros2", library="snakebot")
            if metadata:
                self._writer.add_metadata("snakebot", dict(metadata))
            self._flush()  # the header: a full disk or a device that refuses it fails here
        self._measured = ros2_msgs.JointStates(self.joint_names)
        self._sent = ros2_msgs.JointStates(self.joint_names, measured=False)
        self._body = ros2_msgs.Transforms(
            ros2_msgs.WORLD_FRAME, [ros2_msgs.BODY_FRAME], single=True
        )
        self._poses: LinkPoses | None = None
        self._links: ros2_msgs.Transforms | None = None
        self._t0: float | None = None
        self._next_tf = self._next_status = -math.inf
        self._next_flush = 0.0
        self._window = RunWindow()
        self._start_com: np.ndarray | None = None

    @contextlib.contextmanager
    def _failures(self, what: str) -> Iterator[None]:
        try:
            yield
        except OSError as exc:
            with contextlib.suppress(Exception):
                self._abandon()
            raise OutputError(self.path, f"{what}: {exc.strerror or exc}") from exc

    def time_ns(self, time_s: float) -> int:
        """Stamp for robot time ``time_s``: the start's wall clock plus robot time, ns."""
        if self._t0 is None:
            self._t0 = time_s
        return self._epoch_ns + round((time_s - self._t0) * 1e9)

    def __call__(self, record: CycleRecord) -> None:
        """Write one cycle: the joint states and the command sent, ``/tf`` and
        ``/diagnostics`` when due; OutputError naming the file when it cannot be written."""
        if self._writer is None:
            raise OutputError(self.path, "the MCAP file is closed")
        state = record.state
        now_ns = self.time_ns(state.time_s)
        com = None if record.body is None else record.body.com_m
        if com is not None and self._start_com is None:
            self._start_com = com.copy()
        with self._failures("cannot write the MCAP file"):
            measured = self._measured(
                now_ns, state.position_rad, state.velocity_rad_s, state.effort_nm
            )
            self._write(ros2_msgs.JOINT_STATES_TOPIC, measured, now_ns)
            self._write(ros2_msgs.COMMAND_TOPIC, self._sent(now_ns, record.command_rad), now_ns)
            if record.body is not None:
                pose = self._body(now_ns, record.body.com_m, record.body.head_quat)
                self._write(ros2_msgs.BODY_POSE_TOPIC, pose, now_ns)
            self.rows += 1
            self._window.add(state.time_s, record.tracking_error_rad, com)
            if self._geometry is not None and state.time_s >= self._next_tf:
                self._next_tf = next_due(self._next_tf, state.time_s, self.tf_rate_hz)
                self._write_tf(now_ns, state.position_rad)
            if state.time_s >= self._next_status:
                self._next_status = next_due(self._next_status, state.time_s, self.status_rate_hz)
                self._write_diagnostics(now_ns, state.time_s, com)
            if state.time_s - (self._t0 or 0.0) >= self._next_flush:
                self._next_flush += MCAP_FLUSH_S
                self._flush()

    def _write(self, topic: str, data: bytes, time_ns: int) -> None:
        channel = self._channels.get(topic)
        if channel is None:  # on its first message: a topic never written has no channel
            channel = self._channels[topic] = self._register(topic)
        self._writer.add_message(channel, log_time=time_ns, data=data, publish_time=time_ns)

    def _register(self, topic: str) -> int:
        kind = ros2_msgs.TOPIC_TYPES[topic]
        schema = self._schemas.get(kind)
        if schema is None:
            text = ros2_msgs.DEFINITIONS[kind].encode()
            schema = self._schemas[kind] = self._writer.register_schema(kind, "ros2msg", text)
        channel: int = self._writer.register_channel(topic, "cdr", schema)
        return channel

    def _write_tf(self, now_ns: int, position_rad: np.ndarray) -> None:
        geometry = self._geometry
        assert geometry is not None
        if self._poses is None or self._links is None:
            from snakebot.backends.twin.model_builder import link_name

            self._poses = geometry.poses()
            links = [link_name(i) for i in range(geometry.link_count)]
            self._links = ros2_msgs.Transforms(ros2_msgs.WORLD_FRAME, links)
        xpos, xquat = self._poses.poses(position_rad)
        self._write(ros2_msgs.TF_TOPIC, self._links(now_ns, xpos, xquat), now_ns)

    def _write_diagnostics(self, now_ns: int, time_s: float, com: np.ndarray | None) -> None:
        readings, window = self._readings, self._window
        alerts = tuple(readings.alerts()) if readings.alerts is not None else ()
        distance = None
        if com is not None and self._start_com is not None:
            distance = float(np.hypot(*(com[:2] - self._start_com[:2])))
        metrics: dict[str, object] = {
            "time_s": time_s,
            "cycles": self.rows,
            "rate_hz": self.rate_hz,
            "achieved_rate_hz": window.rate_hz(),
            "overruns": readings.overruns() if readings.overruns is not None else 0,
            "tracking_rms_rad": window.tracking_rms(),
            "distance_m": distance,
            "speed_mps": window.speed_mps(),
        }
        metrics.update({f"alert{i}": text for i, text in enumerate(alerts)})
        window.restart()
        run = ros2_msgs.diagnostic_status(
            f"{NODE_NAME}: run",
            ros2_msgs.WARN if alerts else ros2_msgs.OK,
            "; ".join(alerts) or "OK",
            metrics,
            hardware_id=self.robot_name,
        )
        health = dict(readings.health()) if readings.health is not None else {}
        faults = dict(readings.faults()) if readings.faults is not None else {}
        statuses = [*self._servo_statuses(health, faults), run]
        self._write(
            ros2_msgs.DIAGNOSTICS_TOPIC, ros2_msgs.diagnostic_array(now_ns, statuses), now_ns
        )
        self._write(ros2_msgs.RUN_METRICS_TOPIC, ros2_msgs.diagnostic_status_message(run), now_ns)

    def _servo_statuses(
        self, health: Mapping[str, np.ndarray], faults: Mapping[int, Sequence[str]]
    ) -> list[ros2_msgs.Status]:
        statuses = []
        for index, (name, servo) in enumerate(zip(self.joint_names, self.servo_ids, strict=True)):
            errors = list(faults.get(servo, ()))
            values: dict[str, object] = {"servo_id": servo}
            values.update({key: float(np.asarray(v)[index]) for key, v in health.items()})
            values["hardware_errors"] = ", ".join(errors)
            statuses.append(
                ros2_msgs.diagnostic_status(
                    f"{NODE_NAME}: {name}",
                    ros2_msgs.ERROR if errors else ros2_msgs.OK,
                    ", ".join(errors) or "OK",
                    values,
                    hardware_id=f"servo {servo}",
                )
            )
        return statuses

    def _flush(self) -> None:
        """Close the open chunk and write it out."""
        self._writer.flush()

    def _abandon(self) -> None:
        """Give up on a file that failed to write: what was flushed before stays on disk."""
        stream, self._stream, self._writer = self._stream, None, None
        if stream is not None:
            stream.close()

    def close(self) -> None:
        """Finish the file (its summary and index); idempotent. OutputError naming the file if
        it cannot be finished: what was flushed before stays on disk."""
        writer, stream = self._writer, self._stream
        self._writer = self._stream = None
        if writer is None:
            return
        try:
            writer.finish()
            assert stream is not None
            stream.close()
        except OSError as exc:
            with contextlib.suppress(OSError):
                if stream is not None:
                    stream.close()
            raise OutputError(self.path, f"cannot finish the MCAP file: {exc.strerror}") from exc

    def __enter__(self) -> Ros2McapRecorder:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()
