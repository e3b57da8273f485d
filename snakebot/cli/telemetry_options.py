"""``--log``, ``--foxglove[=PORT]`` and ``--mcap FILE`` for ``run`` and ``drive``: the options and
the sinks they open (CSV with its JSON sidecar, the Foxglove server, the MCAP file: the Foxglove
channels in JSON, or with ``--mcap-encoding ros2`` standard ROS 2 messages in CDR)."""

from __future__ import annotations

import argparse
import contextlib
import ipaddress
import json
import socket
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from snakebot.backends.base import Backend
from snakebot.cli.backend_options import backend_spec
from snakebot.cli.common import add_force_option, check_writable
from snakebot.errors import OutputError, UsageError
from snakebot.telemetry import CsvTelemetryWriter, column_names
from snakebot.telemetry.sink import CycleSink, combine
from snakebot.telemetry.ws_gate import FOXGLOVE_ORIGINS, MAX_CLIENTS

DEFAULT_PORT = 8765
MCAP_ENCODINGS = ("json", "ros2")


def _port(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a TCP port number, got {text!r}") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"expected a TCP port 0-65535 (0: any free), got {value}")
    return value


def _client_limit(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of clients, got {text!r}") from None
    if not 1 <= value <= 1000:
        raise argparse.ArgumentTypeError(f"expected 1-1000 clients, got {value}")
    return value


def _origin(text: str) -> str:
    origin = text.strip().rstrip("/")
    scheme, sep, rest = origin.partition("://")
    if not sep or scheme not in ("http", "https") or not rest or "/" in rest:
        raise argparse.ArgumentTypeError(
            f"expected an origin like https://viz.example.org (scheme://host[:port]), got {text!r}"
        )
    return origin


def add_telemetry_options(parser: argparse.ArgumentParser) -> None:
    """Add ``--foxglove[=PORT]``, ``--foxglove-host`` and ``--mcap`` (``--log`` stays the
    command's own)."""
    parser.add_argument(
        "--foxglove",
        nargs="?",
        const=DEFAULT_PORT,
        type=_port,
        metavar="PORT",
        help=f"stream live to Foxglove: a WebSocket server on 127.0.0.1:PORT (default "
        f"{DEFAULT_PORT}; 0: any free port; extra: snakebot[foxglove]); the twin then keeps to "
        "the wall clock; docs/driving.md has the layout",
    )
    parser.add_argument(
        "--foxglove-host",
        default="127.0.0.1",
        metavar="HOST",
        help="address the --foxglove server binds (default 127.0.0.1: this machine only; "
        "0.0.0.0 or ::: every network, with a warning)",
    )
    parser.add_argument(
        "--foxglove-origin",
        action="append",
        type=_origin,
        default=[],
        metavar="ORIGIN",
        help=f"also let browser pages from ORIGIN connect (repeatable; always allowed: pages of "
        f"this machine, {', '.join(FOXGLOVE_ORIGINS)} and clients that are not browsers)",
    )
    parser.add_argument(
        "--foxglove-max-clients",
        type=_client_limit,
        default=MAX_CLIENTS,
        metavar="N",
        help=f"serve at most N Foxglove clients at once (default {MAX_CLIENTS})",
    )
    parser.add_argument(
        "--mcap", type=Path, metavar="FILE", help="record the Foxglove channels to an MCAP file"
    )
    parser.add_argument(
        "--mcap-encoding",
        choices=MCAP_ENCODINGS,
        default="json",
        help="what --mcap writes: json (default: the Foxglove channels) or ros2 (standard ROS 2 "
        "messages in CDR that rosbag2 and Foxglove read; extra: snakebot[ros2-mcap]; "
        "docs/ros2.md)",
    )
    add_force_option(parser)


def check_outputs(args: argparse.Namespace, *others: tuple[Path | None, str]) -> None:
    """Refuse, before anything is written or moves, every output of ``run``/``drive`` that
    exists (without ``--force``) or cannot be written: ``--log`` and its JSON sidecar,
    ``--mcap``, and ``others`` (path or None, what it is)."""
    from snakebot.telemetry.sidecar import sidecar_path

    if ros2_recording(args):
        from snakebot.telemetry.ros2_mcap import mcap_writer_module

        mcap_writer_module()  # a missing extra stops the run before a file is touched
    elif getattr(args, "mcap_encoding", "json") != "json" and args.mcap is None:
        raise UsageError(f"--mcap-encoding {args.mcap_encoding} goes with --mcap FILE")
    outputs: list[tuple[Path | None, str]] = [(args.log, "log")]
    if args.log:
        outputs.append((sidecar_path(args.log), "log's JSON sidecar"))
    outputs += [(args.mcap, "MCAP file"), *others]
    for path, what in outputs:
        if path is not None:
            check_writable(path, what, force=args.force)


@dataclass
class Telemetry:
    """The sinks a run writes to: ``log`` gets every cycle's record (None: none asked for)."""

    log: CycleSink | None = None
    csv: CsvTelemetryWriter | None = None
    foxglove: Any = None
    ros2_mcap: CycleSink | None = None
    summary: dict[str, object] = field(default_factory=dict)


def ros2_recording(args: argparse.Namespace) -> bool:
    """True when ``--mcap`` records in the ROS 2 encoding (``--mcap-encoding ros2``)."""
    return args.mcap is not None and getattr(args, "mcap_encoding", "json") == "ros2"


def open_telemetry(
    stack: contextlib.ExitStack,
    args: argparse.Namespace,
    *,
    command: str,
    robot: Any,
    backend: Backend,
    rate_hz: float,
    gait: Mapping[str, Any],
) -> Telemetry:
    """Open what ``--log``, ``--foxglove`` and ``--mcap`` ask for, closed by ``stack``.

    Call before the backend connects, after :func:`check_outputs`: a port that cannot be bound
    or a missing extra stops the run before a servo moves.
    """
    telemetry = Telemetry()
    if args.log:
        telemetry.csv = stack.enter_context(CsvTelemetryWriter(args.log, robot.joint_count))
        from snakebot.telemetry.sidecar import write_sidecar

        sidecar = write_sidecar(
            args.log,
            command=command,
            robot=robot,
            backend=backend_spec(args).name,
            rate_hz=rate_hz,
            columns=column_names(robot.joint_count),
            extra=gait,
        )
        telemetry.summary["log_sidecar"] = str(sidecar)
    port = getattr(args, "foxglove", None)
    ros2 = ros2_recording(args)
    if ros2:
        telemetry.ros2_mcap = open_ros2_mcap(stack, args, robot, backend, rate_hz, command, gait)
    if port is not None or (args.mcap is not None and not ros2):
        mcap = None if ros2 else args.mcap
        telemetry.foxglove = sink = _open_foxglove(
            stack, args, robot, backend, rate_hz, command, mcap
        )
        if sink.port is not None:
            telemetry.summary["foxglove"] = client_url(args.foxglove_host, sink.port)
            # at the end of the run, just before the server closes
            stack.callback(lambda: telemetry.summary.update(foxglove_clients=sink.client_counts()))
    if args.mcap is not None:
        telemetry.summary["mcap"] = str(args.mcap)
    telemetry.log = combine([telemetry.csv, telemetry.foxglove, telemetry.ros2_mcap])
    return telemetry


def open_ros2_mcap(
    stack: contextlib.ExitStack,
    args: argparse.Namespace,
    robot: Any,
    backend: Backend,
    rate_hz: float,
    command: str,
    gait: Mapping[str, Any],
) -> CycleSink:
    """The ROS 2 recording ``--mcap`` asks for (``run``, ``drive``, ``ros2``), closed by
    ``stack``: every cycle of ``robot`` on ``backend`` (not yet connected) at ``rate_hz``;
    ``command`` and ``gait`` go into its metadata."""
    from snakebot.backends.twin.model_builder import joint_name
    from snakebot.telemetry.robot_scene import robot_geometry
    from snakebot.telemetry.ros2_mcap import Ros2McapRecorder, backend_readings

    names = [joint_name(i) for i in range(robot.joint_count)]
    metadata = {
        "command": command,
        "robot": str(getattr(robot, "name", "")),
        "backend": backend_spec(args).name,
        "rate_hz": f"{rate_hz:g}",
        "joint_names": ",".join(names),
        "gait": json.dumps(gait, default=str),
    }
    recorder = Ros2McapRecorder(
        args.mcap,
        joint_names=names,
        servo_ids=getattr(robot, "servo_ids", range(robot.joint_count)),
        rate_hz=rate_hz,
        geometry=robot_geometry(robot, backend),
        readings=backend_readings(backend),
        robot_name=metadata["robot"],
        metadata=metadata,
    )
    return stack.enter_context(recorder)


def _open_foxglove(
    stack: contextlib.ExitStack,
    args: argparse.Namespace,
    robot: Any,
    backend: Backend,
    rate_hz: float,
    command: str,
    mcap: Path | None,
) -> Any:
    from snakebot.drive.observers import backend_readings
    from snakebot.telemetry.foxglove_live import FoxgloveTelemetry, SlowReadings, TelemetryOptions
    from snakebot.telemetry.robot_scene import robot_geometry

    options = TelemetryOptions(
        port=args.foxglove,
        host=args.foxglove_host,
        mcap_path=mcap,
        origins=tuple(getattr(args, "foxglove_origin", ())),
        max_clients=getattr(args, "foxglove_max_clients", MAX_CLIENTS),
    )
    health, alerts = backend_readings(backend)
    readings = SlowReadings(health=health, alerts=alerts, overruns=lambda: backend.stats.overruns)
    try:
        sink = stack.enter_context(
            FoxgloveTelemetry(
                options,
                servo_ids=getattr(robot, "servo_ids", range(robot.joint_count)),
                rate_hz=rate_hz,
                geometry=robot_geometry(robot, backend),
                readings=readings,
                drive=command == "drive",
            )
        )
    except OutputError as exc:
        if exc.path != f"{options.host}:{options.port}":
            raise
        # the port is taken: say which option chose it
        raise OutputError(f"--foxglove={args.foxglove}", exc.reason) from exc
    if sink.port is not None:
        url = client_url(options.host, sink.port)
        print(
            f"snakebot: Foxglove: open connection {url} (layout: docs/foxglove/"
            "snakebot-layout.json)",
            file=sys.stderr,
            flush=True,
        )
        if not _loopback(options.host):
            print(
                f"snakebot: warning: the Foxglove server on {options.host} is reachable from "
                f"the network (other machines: ws://{_bracket(socket.gethostname())}:"
                f"{sink.port}); anyone who reaches it sees the stream, the protocol has no "
                "password",
                file=sys.stderr,
                flush=True,
            )
    return sink


def client_url(host: str, port: int) -> str:
    """A URL a client on this machine can open for a server bound to ``host``: a wildcard
    (``0.0.0.0``, ``::``) becomes its loopback, an IPv6 address goes in brackets."""
    address = _address(host)
    if address is not None and address.is_unspecified:
        host = "127.0.0.1" if address.version == 4 else "::1"
    return f"ws://{_bracket(host)}:{port}"


def _address(host: str) -> ipaddress.IPv4Address | ipaddress.IPv6Address | None:
    try:
        return ipaddress.ip_address(host.strip("[]"))
    except ValueError:
        return None


def _bracket(host: str) -> str:
    address = _address(host)
    return f"[{address}]" if address is not None and address.version == 6 else host


def _loopback(host: str) -> bool:
    address = _address(host)
    return host == "localhost" if address is None else address.is_loopback


def drive_observer(telemetry: Telemetry) -> Any:
    """A drive observer writing each cycle to the sinks, and the live gait's status to
    Foxglove's ``/drive``; None when there is no sink."""
    log, foxglove = telemetry.log, telemetry.foxglove
    if log is None:
        return None

    def observe(cycle: Any) -> None:
        log(cycle)
        if foxglove is not None:
            status = cycle.status
            controls = status.controls or status.setpoint
            foxglove.drive(
                cycle.time_s,
                {
                    "gait": status.gait,
                    "mode": status.mode,
                    "speed": controls.speed,
                    "turn": controls.turn,
                    "amplitude": controls.amplitude,
                    "wavelength": controls.wavelength,
                    "blend": status.blend,
                },
                cycle.target_rad,
                cycle.keys,
            )

    return observe
