"""Live telemetry to Foxglove (its SDK's WebSocket server) and to an MCAP file, per cycle.

One Foxglove ``Context`` carries the channels (see :mod:`snakebot.telemetry.schemas`); the
WebSocket server and the MCAP writer are its sinks, so the file holds exactly what a live client
sees. Every cycle goes to ``/joints``; the 3-D scene (``/tf`` link frames, ``/scene`` capsules)
at ``scene_rate_hz``; servo health, servo errors and run metrics at ``status_rate_hz``. Messages
are timed at the wall clock of the start plus robot time, so a twin run that is faster than real
time plays back at robot speed.

The SDK serialises and sends from its own threads; its server listens on a loopback port of its
own behind a :class:`~snakebot.telemetry.ws_gate.WebSocketGate` on the address asked for, which
checks each client's Origin, serves at most ``max_clients`` and disconnects a client that stops
reading, so no number of clients costs the control loop its rate (tools/bench_foxglove_clients.py,
docs/benchmarks.md). Failed sends are counted (:meth:`FoxgloveTelemetry.client_counts`), not
printed. A cycle costs the control thread about 0.1 ms (tools/bench_telemetry.py).

The MCAP file is complete once closed; a killed run loses the open chunk, while the CSV log
(``--log``) loses nothing and ``snakebot log export`` rebuilds the MCAP from it.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from snakebot.errors import MissingDependencyError, OutputError
from snakebot.telemetry import schemas
from snakebot.telemetry.run_window import RunWindow, next_due
from snakebot.telemetry.scene import LinkPoses, frame_transforms, scene_update
from snakebot.telemetry.sdk_logs import SendErrors, quiet_sink_errors
from snakebot.telemetry.ws_gate import MAX_CLIENTS, STALL_S, WebSocketGate

if TYPE_CHECKING:
    from snakebot.control.cycle import CycleRecord

INSTALL = "pip install 'snakebot[foxglove]'"
LOCALHOST = "127.0.0.1"
SCENE_REFRESH_S = 1.0  # the capsules again, for clients that join late and for MCAP seeks
MCAP_FLUSH_S = 1.0  # close the MCAP chunk: a killed run loses at most this much of the file


@dataclass(frozen=True)
class TelemetryOptions:
    """Where the stream goes: a WebSocket server (``port`` None: none; 0: any free port) and/or
    an MCAP file; how often the scene (Hz) and the slow channels (Hz) are sent; which browser
    origins besides this machine's and Foxglove's may connect, how many clients at once, and how
    long (s) one may take nothing before it is disconnected."""

    port: int | None = None
    host: str = LOCALHOST
    mcap_path: Path | None = None
    origins: tuple[str, ...] = ()
    max_clients: int = MAX_CLIENTS
    stall_s: float = STALL_S
    scene_rate_hz: float = 30.0
    status_rate_hz: float = 4.0


@dataclass(frozen=True)
class Geometry:
    """What the scene draws: links (count, length m, radius m) and where their poses come from.

    ``poses`` is called on the first cycle (the twin's model exists only once it is connected).
    """

    link_count: int
    length_m: float
    radius_m: float
    poses: Callable[[], LinkPoses]


@dataclass(frozen=True)
class SlowReadings:
    """The backend's slow readings: ``health`` (``temperature_c``, ``input_voltage_v``: (N,)
    arrays where the backend has them), ``alerts`` (what went wrong so far) and ``overruns``."""

    health: Callable[[], Mapping[str, np.ndarray]] | None = None
    alerts: Callable[[], Sequence[str]] | None = None
    overruns: Callable[[], int] | None = None


def foxglove_module() -> Any:
    """The Foxglove SDK, or MissingDependencyError with the install command."""
    try:
        import foxglove
    except ImportError as exc:
        raise MissingDependencyError(
            f"live Foxglove views and MCAP recordings need the Foxglove SDK: {INSTALL}"
        ) from exc
    return foxglove


def open_channels(context: Any, topics: Sequence[str]) -> dict[str, Any]:
    """JSON channels on ``context`` for ``topics`` (keys of :data:`schemas.CHANNELS`)."""
    foxglove = foxglove_module()
    channels = {}
    for topic in topics:
        schema = schemas.CHANNELS[topic]
        channels[topic] = foxglove.Channel(
            topic,
            schema=foxglove.Schema(
                name=schema["title"], encoding="jsonschema", data=schemas.schema_bytes(schema)
            ),
            message_encoding="json",
            context=context,
        )
    return channels


class FoxgloveTelemetry:
    """A :class:`~snakebot.control.cycle.CycleSink` streaming each cycle's record to Foxglove
    and MCAP.

    Opening starts the server and creates the file: OutputError naming ``host:port`` when the
    port cannot be bound, OutputError naming the file when it cannot be created or finished,
    MissingDependencyError without the SDK.
    """

    def __init__(
        self,
        options: TelemetryOptions,
        *,
        servo_ids: Sequence[int],
        rate_hz: float,
        geometry: Geometry | None = None,
        readings: SlowReadings | None = None,
        drive: bool = False,
        start_epoch_ns: int | None = None,
    ) -> None:
        foxglove = foxglove_module()
        self.options = options
        self.rows = 0
        self.servo_ids = [int(i) for i in servo_ids]
        self.rate_hz = rate_hz
        self._geometry = geometry
        self._readings = readings or SlowReadings()
        self._epoch_ns = time.time_ns() if start_epoch_ns is None else start_epoch_ns
        self._context = foxglove.Context()
        self._server: Any = None
        self._gate: WebSocketGate | None = None
        self._send_errors: SendErrors | None = None
        self._writer: Any = None
        try:
            self._open_sinks(foxglove)
        except BaseException:
            with contextlib.suppress(Exception):  # what failed to open is what to report
                self.close()
            raise
        topics = [schemas.JOINTS_TOPIC, schemas.METRICS_TOPIC, schemas.ERRORS_TOPIC]
        topics += [schemas.HEALTH_TOPIC]
        topics += [schemas.DRIVE_TOPIC] if drive else []
        topics += [schemas.TF_TOPIC, schemas.SCENE_TOPIC] if geometry is not None else []
        self._channels = open_channels(self._context, topics)
        self._poses: LinkPoses | None = None
        self._t0: float | None = None
        self._next_scene = self._next_status = self._next_refresh = -math.inf
        self._next_flush = 0.0
        self._window = RunWindow()
        self._start_com: np.ndarray | None = None
        self._last_errors: tuple[str, ...] | None = None

    def _open_sinks(self, foxglove: Any) -> None:
        options = self.options
        if options.mcap_path is not None:
            path = options.mcap_path
            quiet_sink_errors()
            try:
                self._writer = foxglove.open_mcap(path, allow_overwrite=True, context=self._context)
            except OSError as exc:
                raise OutputError(path, f"cannot write the MCAP file: {exc.strerror}") from exc
            self._flush()  # the header: a full disk or a device that refuses it fails here
        if options.port is not None:
            where = f"{options.host}:{options.port}"
            self._send_errors = SendErrors.install()
            try:
                self._server = foxglove.start_server(
                    name="snakebot", host=LOCALHOST, port=0, context=self._context
                )
            except RuntimeError as exc:
                reason = str(exc).removeprefix("FoxgloveError: ")
                raise OutputError(where, f"cannot start the Foxglove server: {reason}") from exc
            try:
                self._gate = WebSocketGate(
                    options.host,
                    options.port,
                    int(self._server.port),
                    origins=options.origins,
                    max_clients=options.max_clients,
                    stall_s=options.stall_s,
                )
            except OSError as exc:
                raise OutputError(
                    where,
                    f"cannot serve Foxglove there: {exc.strerror or exc} (another snakebot or "
                    "Foxglove bridge there? pick another port)",
                ) from exc

    @property
    def port(self) -> int | None:
        """The server's port (the one picked when asked for 0), or None without a server."""
        return None if self._gate is None else self._gate.port

    @property
    def clients(self) -> int:
        """WebSocket clients connected now (0 without a server)."""
        return 0 if self._gate is None else self._gate.clients

    def client_counts(self) -> dict[str, int]:
        """What became of the WebSocket clients so far: accepted, refused_origin, refused_full,
        dropped_slow, bad_request (see :class:`~snakebot.telemetry.ws_gate.GateCounts`) and
        send_errors (messages the SDK failed to send); empty without a server."""
        if self._gate is None:
            return {}
        counts = self._gate.counts.as_dict()
        counts["send_errors"] = self._send_errors.count if self._send_errors is not None else 0
        return counts

    def time_ns(self, time_s: float) -> int:
        """Message time for robot time ``time_s``: the start's wall clock plus robot time."""
        if self._t0 is None:
            self._t0 = time_s
        return self._epoch_ns + round((time_s - self._t0) * 1e9)

    def __call__(self, record: CycleRecord) -> None:
        """Send one cycle's record: ``/joints`` every cycle (its ``cycle`` counted from 0, as
        in the CSV log), the scene and the status channels at their own rates."""
        state = record.state
        time_s, command, position = state.time_s, record.command_rad, state.position_rad
        com = None if record.body is None else record.body.com_m
        cycle, velocity, effort = record.cycle - 1, state.velocity_rad_s, state.effort_nm
        now_ns = self.time_ns(time_s)
        error = command - position
        message: dict[str, Any] = {
            "time_s": time_s,
            "cycle": cycle,
            "command_rad": _short(command),
            "position_rad": _short(position),
            "velocity_rad_s": _short(velocity),
            "effort_nm": _short(effort),
            "tracking_error_rad": _short(error),
        }
        if com is not None:
            message["com_m"] = _short(com)
            if self._start_com is None:
                self._start_com = com.copy()
        self._channels[schemas.JOINTS_TOPIC].log(message, log_time=now_ns)
        self.rows += 1
        self._window.add(time_s, error, com)
        if self._geometry is not None and time_s >= self._next_scene:
            self._next_scene = next_due(self._next_scene, time_s, self.options.scene_rate_hz)
            self._send_scene(now_ns, time_s, position)
        if time_s >= self._next_status:
            self._next_status = next_due(self._next_status, time_s, self.options.status_rate_hz)
            self._send_status(now_ns, time_s, com)
        if self._writer is not None and time_s - (self._t0 or 0.0) >= self._next_flush:
            self._next_flush += MCAP_FLUSH_S
            self._flush()

    def _flush(self) -> None:
        """Finish the MCAP chunk and write it out; OutputError naming the file if that fails
        (the SDK only logs a failed write, a flush raises it)."""
        try:
            self._writer.flush()
        except (OSError, RuntimeError) as exc:
            reason = str(exc).removeprefix("FoxgloveError: ")
            raise OutputError(
                self.options.mcap_path or "", f"cannot write the MCAP file: {reason}"
            ) from exc

    def drive(
        self, time_s: float, status: Mapping[str, Any], target: np.ndarray, keys: Sequence[str]
    ) -> None:
        """Send the drive's live-gait status for the cycle at ``time_s`` (``/drive``)."""
        message = {"time_s": time_s, **status, "target_rad": target.tolist(), "keys": list(keys)}
        self._channels[schemas.DRIVE_TOPIC].log(message, log_time=self.time_ns(time_s))

    def _send_scene(self, now_ns: int, time_s: float, position: np.ndarray) -> None:
        geometry = self._geometry
        assert geometry is not None
        if self._poses is None:
            self._poses = geometry.poses()
        if time_s >= self._next_refresh:
            self._next_refresh = time_s + SCENE_REFRESH_S
            update = scene_update(now_ns, geometry.link_count, geometry.length_m, geometry.radius_m)
            self._channels[schemas.SCENE_TOPIC].log(update, log_time=now_ns)
        xpos, xquat = self._poses.poses(position)
        self._channels[schemas.TF_TOPIC].log(frame_transforms(now_ns, xpos, xquat), log_time=now_ns)

    def _send_status(self, now_ns: int, time_s: float, com: np.ndarray | None) -> None:
        readings = self._readings
        window = self._window
        metrics: dict[str, Any] = {
            "time_s": time_s,
            "cycles": self.rows,
            "rate_hz": self.rate_hz,
            "achieved_rate_hz": window.rate_hz(),
            "overruns": readings.overruns() if readings.overruns is not None else 0,
            "tracking_rms_rad": window.tracking_rms(),
            "distance_m": None,
            "speed_mps": window.speed_mps(),
        }
        if com is not None and self._start_com is not None:
            metrics["distance_m"] = float(np.hypot(*(com[:2] - self._start_com[:2])))
        self._channels[schemas.METRICS_TOPIC].log(metrics, log_time=now_ns)
        window.restart()
        health = dict(readings.health()) if readings.health is not None else {}
        if health:
            message: dict[str, Any] = {"time_s": time_s, "servo_ids": self.servo_ids}
            message.update({key: np.asarray(value).tolist() for key, value in health.items()})
            self._channels[schemas.HEALTH_TOPIC].log(message, log_time=now_ns)
        errors = tuple(readings.alerts()) if readings.alerts is not None else ()
        if errors != self._last_errors:  # on change, and once at the start
            self._last_errors = errors
            self._channels[schemas.ERRORS_TOPIC].log(
                {"time_s": time_s, "count": len(errors), "errors": list(errors)}, log_time=now_ns
            )

    def close(self) -> None:
        """Finish the MCAP file and stop the server; idempotent. OutputError naming the file if
        it cannot be finished (what was written before stays on disk)."""
        writer, self._writer = self._writer, None
        server, self._server = self._server, None
        gate, self._gate = self._gate, None
        if gate is not None:
            gate.stop()
        if server is not None:
            server.stop()
        if self._send_errors is not None:
            self._send_errors.remove()
        if writer is not None:
            try:
                writer.close()
            except (OSError, RuntimeError) as exc:
                raise OutputError(
                    self.options.mcap_path or "", f"cannot finish the MCAP file: {exc}"
                ) from exc

    def __enter__(self) -> FoxgloveTelemetry:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def _short(values: np.ndarray) -> list[float]:
    """Six decimals (1 urad, 1 um, 1 uN m: finer than any servo measures): a third of the JSON
    of full float precision, and it compresses twice as well."""
    rounded: list[float] = np.round(values, 6).tolist()
    return rounded
