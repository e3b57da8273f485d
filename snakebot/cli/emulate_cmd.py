"""``snakebot emulate``: a virtual servo chain on a pseudo-terminal, with optional twin physics.

Servos start with factory settings (Return Delay Time 500 µs, Status Return Level 2, default gains
and limits) at the robot's IDs and baud rate, or, with ``--fresh N``, not at all: each line
``plug`` on stdin (or SIGUSR1) then connects the next factory-fresh servo (ID 1 at its factory
rate), the way a user adds servos one at a time. ``power`` on stdin power-cycles every servo. With
``--state-file`` every servo's EEPROM is kept on disk across runs (emulated power cycles).

The servos speak the robot's ``[bus] protocol`` (``--protocol`` overrides it: an X-series servo
then has Protocol Type 1 and answers Protocol 1.0 only); ``--also MODEL:IDS[:PROTOCOL]`` adds
servos of another model to the same wire, so one chain holds both protocols.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import queue
import signal
import sys
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Any

from snakebot.cli.common import add_robot_option, baud_arg, print_json, robot_name
from snakebot.cli.terrain_options import add_terrain_options, refuse_friction_model, twin_ground
from snakebot.config import RobotConfig, load_robot
from snakebot.errors import ConfigError, UsageError
from snakebot.servo import FACTORY_BAUD

if TYPE_CHECKING:
    import numpy as np

    from snakebot.emulation.bench import ServoBench
    from snakebot.emulation.chain import EmulatedChain
    from snakebot.emulation.physics import TwinMotion
    from snakebot.emulation.pty_server import PtyServer
    from snakebot.emulation.virtual_servo import VirtualServo
    from snakebot.servo_tables import ServoTable


def add_parser(subparsers: Any) -> None:
    """Register the ``emulate`` command."""
    parser = subparsers.add_parser(
        "emulate",
        help="serve an emulated Dynamixel chain on a pseudo-terminal",
        description="Create a pseudo-terminal that answers like the robot's servo chain (its "
        "model, IDs, baud and protocol, byte for byte). Prints the device path first; serves "
        "until Ctrl-C, SIGTERM or SIGHUP, or until its stdin (a pipe) ends once the process "
        "that started it has exited. "
        "Stdin commands: 'plug' (also SIGUSR1) connects the next --fresh servo, 'power' "
        "power-cycles every servo.",
    )
    add_robot_option(parser)
    parser.add_argument("--baud", type=baud_arg, help="line rate (default: the robot's bus.baud)")
    parser.add_argument(
        "--protocol",
        type=protocol_arg,
        metavar="{1,2}",
        help="the protocol the robot's servos speak (default: its bus.protocol); "
        "1 on an X-series robot sets Protocol Type 1",
    )
    parser.add_argument(
        "--also",
        type=also_arg,
        action="append",
        default=[],
        metavar="MODEL:IDS[:PROTOCOL]",
        help="add servos of MODEL with IDS (e.g. 7-9,12) on the same wire, in "
        "PROTOCOL (default: the model's own); repeatable",
    )
    parser.add_argument(
        "--physics",
        action="store_true",
        help="back the servos with the MuJoCo twin in real time (goals, torque and Position P/D "
        "gains from their registers); print its summary on exit",
    )
    add_terrain_options(parser)
    parser.add_argument(
        "--wrap-on-pole",
        metavar="GAIT[:KEY=VALUE,...]",
        help="with --physics --terrain pole: start the twin coiled around the pole in GAIT's "
        "t = 0 shape (e.g. rolling_helix:pole_radius_m=0.052,pitch_m_per_rad=0.03), the "
        "servos holding it, as a snake wrapped by hand (docs/twin.md)",
    )
    parser.add_argument("--pty", action="store_true", required=True, help="serve on a pty")
    parser.add_argument("--json", action="store_true", help='print {"port": ...} and JSON summary')
    parser.add_argument(
        "--fresh",
        type=int,
        default=0,
        metavar="N",
        help="start with no servo connected; N factory-fresh ones (ID 1, "
        "factory baud) wait to be plugged in",
    )
    parser.add_argument(
        "--attached",
        type=int,
        default=0,
        metavar="K",
        help="with --fresh: plug in K at start (K >= 2 share ID 1 and collide)",
    )
    parser.add_argument(
        "--state-file", type=Path, help="keep every servo's EEPROM in this JSON file across runs"
    )
    parser.add_argument(
        "--scramble",
        type=int,
        metavar="SEED",
        help="start the robot's servos with wrong settings (ignored when the state file exists)",
    )
    # writes=False: the state file is the emulated servos' own EEPROM, not an output
    parser.set_defaults(handler=run, writes=False)


@dataclass(frozen=True)
class AlsoServos:
    """One ``--also`` group: a model, its servo IDs and the protocol they speak (None: the
    model's default)."""

    model: str
    ids: tuple[int, ...]
    protocol: float | None


def protocol_arg(text: str) -> float:
    """argparse type: a protocol version, 1 or 2 (1.0 and 2.0 also read)."""
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if value not in (1.0, 2.0):
        raise argparse.ArgumentTypeError(f"expected 1 or 2, got {text!r}")
    return value


def _ids(text: str) -> tuple[int, ...]:
    ids: list[int] = []
    for part in text.split(","):
        low, _, high = part.partition("-")
        first, last = int(low), int(high or low)
        if not 0 <= first <= last <= 252:
            raise ValueError(part)
        ids += range(first, last + 1)
    return tuple(ids)


def also_arg(text: str) -> AlsoServos:
    """argparse type: ``MODEL:IDS[:PROTOCOL]``, IDS a comma list of IDs and ranges (``1-4,7``)."""
    grammar = "expected MODEL:IDS[:PROTOCOL], e.g. AX-12A:7-12 or XL430-W250:1,2:1"
    parts = text.split(":")
    if len(parts) not in (2, 3) or not parts[0]:
        raise argparse.ArgumentTypeError(f"{grammar}, got {text!r}")
    try:
        ids = _ids(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{grammar}: IDS are 0..252 as a comma list of IDs and ranges, got {parts[1]!r}"
        ) from None
    protocol = protocol_arg(parts[2]) if len(parts) == 3 else None
    return AlsoServos(parts[0], ids, protocol)


def _speak(
    servos: Sequence[VirtualServo],
    table: ServoTable,
    protocol: float | None,
    source: str,
    *,
    key: str | None = None,
) -> None:
    """Set the servos' protocol (ConfigError naming `source` and `key` if the model cannot
    speak it)."""
    from snakebot.families import family_for

    try:
        family = family_for(table, protocol)
    except ConfigError as exc:
        has = " and ".join(f"{p:.1f}" for p in table.protocols)
        raise ConfigError(
            source,
            exc.key if key is None else key,
            f"{table.model} servos speak Protocol {has} only, not {exc.key}; expected one of those",
        ) from exc
    if "protocol_type" in table:
        for servo in servos:
            servo.poke("protocol_type", int(family.protocol))


def _also(chain: EmulatedChain, groups: Sequence[AlsoServos], baud: int) -> None:
    """Add every ``--also`` group to the chain (ConfigError on an unknown model, a baud the
    model lacks or an ID already on the chain)."""
    from snakebot.emulation.bench import robot_servos
    from snakebot.servo_tables import UnknownModelError, table_for_model

    for group in groups:
        try:
            table = table_for_model(group.model)
        except UnknownModelError as exc:
            raise ConfigError("--also", group.model, str(exc)) from exc
        taken = sorted(set(group.ids) & {s.servo_id for s in chain.servos})
        if taken:
            raise ConfigError("--also", group.model, f"IDs {taken} are on the chain already")
        try:
            servos = robot_servos(table, group.ids, baud)
        except ValueError as exc:
            raise ConfigError("--also", group.model, str(exc)) from exc
        _speak(servos, table, group.protocol, "--also")
        first = max((s.serial_number for s in chain.servos), default=0) + 1
        for serial, servo in enumerate(servos, start=first):
            servo.serial_number = serial
            chain.add(servo)


def _wrapped_pose(
    args: argparse.Namespace, robot: RobotConfig, ground: dict[str, Any]
) -> np.ndarray | None:
    """``--wrap-on-pole GAIT[:KEY=VALUE,...]``: the gait's t = 0 pose (N,) rad, or None.
    UsageError (exit 2) without a pole terrain or for a bad gait spec."""
    if not args.wrap_on_pole:
        return None
    terrain = ground["terrain"]
    if terrain is None or terrain.name != "pole":
        raise UsageError("--wrap-on-pole needs the pole terrain: add --terrain pole[:...]")
    from snakebot.errors import GaitError
    from snakebot.gaits import make_gait, parse_set_options

    name, _, options = str(args.wrap_on_pole).partition(":")
    try:
        items = [item for item in options.split(",") if item]
        params = parse_set_options(name, items, source="--wrap-on-pole")
        gait = make_gait(
            name, robot.joint_count, params, lower_rad=robot.lower_rad, upper_rad=robot.upper_rad
        )
        pose: np.ndarray = gait.targets(0.0)
        return pose
    except (GaitError, ConfigError) as exc:
        text = str(exc)
        raise UsageError(text if "--wrap-on-pole" in text else f"--wrap-on-pole: {text}") from None


def _bench(
    robot: RobotConfig, args: argparse.Namespace, baud: int
) -> tuple[ServoBench, TwinMotion | None]:
    from snakebot.emulation.bench import ServoBench, robot_servos, scramble
    from snakebot.emulation.chain import EmulatedChain

    if not 0 <= args.attached <= args.fresh:
        raise ConfigError("--attached", "", f"expected 0..{args.fresh} (the --fresh count)")
    if args.fresh and (args.physics or args.scramble is not None):
        raise ConfigError(
            "--fresh", "", "--fresh starts with no robot chain: drop --physics and --scramble"
        )
    if not args.physics:
        if args.terrain or args.wrap_on_pole:
            flag = "--terrain" if args.terrain else "--wrap-on-pole"
            raise UsageError(f"{flag} needs --physics: without it no twin runs under the servos")
        refuse_friction_model(args, "needs --physics: without it no twin runs under the servos")
    motion = None
    if args.fresh:
        chain = EmulatedChain(baud=FACTORY_BAUD)
    elif args.physics:
        from snakebot.emulation.physics import make_twin_chain

        ground = twin_ground(args, robot)
        chain, motion = make_twin_chain(
            robot, baud, **ground, wrapped_pose_rad=_wrapped_pose(args, robot, ground)
        )
        for serial, servo in enumerate(chain.servos, start=1):
            servo.serial_number = serial
    else:
        try:
            servos = robot_servos(robot.servo.name, robot.servo_ids, baud)
        except ValueError as exc:
            raise ConfigError("--baud", "", str(exc)) from exc
        chain = EmulatedChain(servos, baud=baud)
    restoring = args.state_file is not None and args.state_file.exists()
    if args.scramble is not None and not restoring:
        scramble(chain, args.scramble)
    if not args.fresh:
        table = chain.servos[0].table if chain.servos else None
        if table is not None:
            protocol = robot.bus.protocol if args.protocol is None else args.protocol
            # The robot's servos are the bad input (exit 1), whether the protocol came from
            # its file or from --protocol.
            _speak(chain.servos, table, protocol, str(robot.source), key="servo")
    _also(chain, args.also, baud)
    bench = ServoBench(chain, robot.servo.name, fresh=args.fresh, state_path=args.state_file)
    for _ in range(args.attached):
        bench.plug()
    if motion is not None and restoring:
        motion.attach(chain)  # IDs may have changed
    bench.save()
    return bench, motion


def _read_commands(commands: queue.Queue[str], piped_input_ended: threading.Event) -> None:
    for line in sys.stdin:
        commands.put(line.strip().lower() or "plug")
    if _stdin_is_a_pipe():  # a terminal's Ctrl-D or /dev/null's end means nothing
        piped_input_ended.set()


def _stdin_is_a_pipe() -> bool:
    import stat

    try:
        mode = os.fstat(sys.stdin.fileno()).st_mode
    except (OSError, ValueError, AttributeError):
        return False
    return stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode)


class Orphaned:
    """Whether nobody is left to stop the emulator: the pipe on its stdin ended and the process
    that started it exited (it was re-parented). A closed pipe alone is not enough (``echo plug
    | snakebot emulate`` keeps serving), nor is a vanished parent with stdin from a terminal or
    /dev/null (``nohup``, ``setsid``, a job left in the background)."""

    def __init__(self) -> None:
        self.parent_pid = os.getppid()
        self.piped_input_ended = threading.Event()

    def __call__(self) -> bool:
        """True once the emulator is orphaned."""
        return self.piped_input_ended.is_set() and os.getppid() != self.parent_pid


def run(args: argparse.Namespace) -> int:
    """Serve until SIGINT, SIGTERM or SIGHUP, or until orphaned (see :class:`Orphaned`), then
    stop cleanly (saving the state file)."""
    from snakebot.emulation.errors import EmulationError
    from snakebot.emulation.pty_server import PtyServer

    robot = load_robot(robot_name(args, hardware=False, what="emulate"))
    baud = args.baud or robot.bus.baud
    try:
        bench, motion = _bench(robot, args, baud)
    except EmulationError as exc:
        raise ConfigError(args.state_file or "--fresh", "", str(exc)) from exc
    stop = threading.Event()
    commands: queue.Queue[str] = queue.Queue()
    plugs: list[str] = []  # appended by SIGUSR1: a list append takes no lock a handler could block

    def on_signal(signum: int, frame: FrameType | None) -> None:
        stop.set()

    def on_plug(signum: int, frame: FrameType | None) -> None:
        plugs.append("plug")

    handlers: dict[signal.Signals, Any] = {signal.SIGINT: on_signal, signal.SIGTERM: on_signal}
    if os.name == "posix":
        handlers[signal.SIGUSR1] = on_plug
        handlers[signal.SIGHUP] = on_signal  # the terminal it ran in closed
    previous = {sig: signal.signal(sig, handler) for sig, handler in handlers.items()}
    server = PtyServer(bench.chain)
    orphaned = Orphaned()
    threading.Thread(
        target=_read_commands, args=(commands, orphaned.piped_input_ended), daemon=True
    ).start()

    def tick() -> None:
        if orphaned():
            _say(
                f"emulate: stdin closed and the process that started it (PID "
                f"{orphaned.parent_pid}) exited: stopping"
            )
            stop.set()
        while plugs:
            _command(args, bench, plugs.pop())
        while not commands.empty():
            _command(args, bench, commands.get())
        bench.save()

    try:
        server.start()
        _announce(args, robot, server.device_path, baud, bench, motion)
        serve_until(stop, server, tick)
    finally:
        server.stop()
        bench.save()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if motion is not None:
            bench.chain.settle()  # the twin's last steps count in its summary
            motion.twin.close()
    if motion is not None:
        _summary(args, robot, motion, bench)
    return 0


def _say(text: str) -> None:
    with contextlib.suppress(OSError):  # stderr may have gone with the parent
        print(text, file=sys.stderr, flush=True)


def serve_until(stop: threading.Event, server: PtyServer, tick: Callable[[], None]) -> None:
    """Run ``tick`` every 0.1 s until ``stop`` is set; PtyServerCrashedError (a bug, exit 3) as
    soon as the server thread has died, so a dead emulator never looks like a silent bus."""
    while not stop.wait(0.1):
        server.check()
        tick()
    server.check()


def _announce(
    args: argparse.Namespace,
    robot: RobotConfig,
    port: str,
    baud: int,
    bench: ServoBench,
    motion: TwinMotion | None,
) -> None:
    servos = bench.chain.servos
    ids = sorted({s.servo_id for s in servos})
    if args.json:
        listed = [
            {
                "id": s.servo_id,
                "model": s.table.model,
                "protocol": s.protocol,
                "family": _family_name(s),
            }
            for s in servos
        ]
        print_json(
            {
                "port": port,
                "baud": baud,
                "servo_ids": ids,
                "waiting": bench.waiting,
                "servos": listed,
            }
        )
        return
    print(port, flush=True)
    groups: dict[tuple[str, str], list[int]] = {}
    for servo in servos:
        groups.setdefault((servo.table.model, _family_name(servo)), []).append(servo.servo_id)
    chain = ", ".join(
        f"{len(g)} x {model} (IDs {min(g)}..{max(g)}, {family})"
        for (model, family), g in groups.items()
    )
    what = (
        (
            f"{len(servos)} x {robot.servo.name} connected, {bench.waiting} fresh waiting "
            "('plug' on stdin or SIGUSR1 connects one)"
        )
        if args.fresh
        else (f"{robot.name}: {chain} at {baud} baud" + (", twin physics" if motion else ""))
    )
    print(f"{what}; Ctrl-C to stop", file=sys.stderr, flush=True)


def _family_name(servo: VirtualServo) -> str:
    """The servo family the emulated servo speaks now ("dynamixel-p1", "feetech-sts")."""
    from snakebot.families import family_for

    return family_for(servo.table, servo.protocol).name


def _command(args: argparse.Namespace, bench: ServoBench, command: str) -> None:
    from snakebot.emulation.errors import EmulationError

    if command == "plug":
        try:
            servo = bench.plug()
        except EmulationError as exc:
            print(f"emulate: {exc}", file=sys.stderr, flush=True)
            return
        event = {
            "event": "plugged",
            "serial": servo.serial_number,
            "id": servo.servo_id,
            "baud": servo.baud,
            "waiting": bench.waiting,
        }
        text = (
            f"plugged in servo #{servo.serial_number} (ID {servo.servo_id} at {servo.baud} "
            f"baud); {bench.waiting} waiting"
        )
    elif command == "power":
        bench.power_cycle()
        event, text = {"event": "power_cycled"}, "power-cycled every servo"
    else:
        print(f"emulate: unknown command {command!r} (plug, power)", file=sys.stderr, flush=True)
        return
    if args.json:
        print_json(event)
    else:
        print(text, flush=True)


def _summary(
    args: argparse.Namespace, robot: RobotConfig, motion: TwinMotion, bench: ServoBench
) -> None:
    # Both protocols' receivers (one of them idle unless the chain is mixed); a checksum
    # failure counts as a CRC error.
    both, servos = (bench.chain.parser_stats, bench.chain.parser1_stats), bench.chain.servos
    fields = ("received_bytes", "packets", "dropped_bytes", "crc_errors", "stale_resets")
    bus = {
        name: max(getattr(s, name) for s in both)
        if name == "received_bytes"
        else sum(getattr(s, name) for s in both)
        for name in fields
    }
    bus["watchdog_trips"] = sum(s.watchdog_trips for s in servos)
    summary = {"robot": robot.name, "backend": "emulate --physics", **motion.summary(), "bus": bus}
    if args.json:
        print_json(summary)
    else:
        print(
            f"twin: moved {summary['distance_m']:.3f} m at heading "
            f"{summary['heading_deg']:.1f} deg in {summary['duration_s']:.1f} s; bus: "
            f"{bus['packets']} packets, {bus['dropped_bytes']} bytes dropped, "
            f"{bus['watchdog_trips']} watchdog trips"
        )
