"""Every fault the emulated bus can inject, at several rates, under both stop policies.

Each case runs the real ServoChainBackend and runner (snake12 by default, ``--robot`` another:
snake12-ax12a for Protocol 1.0, snake12-sts3215 for Feetech; sidewinding, 100 Hz) through the
unmodified vendor SDK (dynamixel_sdk, scservo_sdk) on the in-process emulator (``dxlemu://``,
virtual time), the servos speaking the robot's protocol,
injects one fault through the emulated chain, lets the run end however it ends, then checks:

- how it ended: completed, a typed error (a SnakebotError subclass, exit 1 in the CLI), or an
  untyped one (anything else: a bug, exit 3). Untyped errors must be 0.
- every Goal Position the servos received (Sync Write or Write to the model's Goal Position,
  decoded from the bytes the host sent in the robot's protocol) against the robot's joint
  limits. Out-of-limit goals must be 0.
- each servo's final state against the stop policy, 1 s after the end with nobody on the bus:
  hold = torque on, Bus Watchdog disarmed (not tripped; where the family has one); limp =
  torque off. A servo the fault took
  off the bus (silent, wrong baud) cannot be reached and is not counted; one whose firmware cut
  its torque (a latched hardware error, a reboot) must be off. Mismatches must be 0.

Usage: python tools/fault_matrix.py [--robot snake12] [--quick] [--duration 2.0] [--json]
Exit status 1 if any must-be-zero figure is not zero.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import struct
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from snakebot.backends.chain import ServoChainBackend
from snakebot.backends.chain.ticks import TickConverter
from snakebot.config import RobotConfig, load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.emulation import (
    EmulatedChain,
    ExternalMotion,
    HardwareError,
    VirtualServo,
    make_chain_for_ids,
    protocol1,
    registered,
)
from snakebot.emulation import protocol as protocol2
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.emulation.port_feetech import EmulatedScsPortHandler
from snakebot.errors import SnakebotError
from snakebot.families import family_for
from snakebot.gaits import make_gait
from snakebot.servo_tables import ServoTable

FAULT_CYCLE = 30
TARGET = 5  # the servo most faults hit


class HostClock:
    """The host's clock: the bus clock minus bus time the host never saw pass."""

    def __init__(self, chain: EmulatedChain) -> None:
        self.chain = chain
        self.unseen_s = 0.0

    def __call__(self) -> float:
        return self.chain.now_s - self.unseen_s

    def stall_unseen(self, seconds: float) -> None:
        """Bus time passes (the watchdogs count it) that the host does not notice."""
        self.chain.advance(seconds)
        self.unseen_s += seconds


@dataclass(frozen=True)
class Fault:
    """One way to break the bus: ``inject(chain, clock, cycle)`` runs after every cycle.

    ``unreachable`` are servo IDs the fault takes off the bus (not counted in the final state);
    ``torque_cut`` are servos whose firmware turns torque off (expected off whatever the policy).
    """

    mode: str
    level: str
    inject: Callable[[EmulatedChain, HostClock, int], None]
    unreachable: tuple[int, ...] = ()
    torque_cut: tuple[int, ...] = ()

    @property
    def name(self) -> str:
        return f"{self.mode}({self.level})" if self.level else self.mode


def at_cycle(
    action: Callable[[EmulatedChain, HostClock], None], cycle: int = FAULT_CYCLE
) -> Callable[[EmulatedChain, HostClock, int], None]:
    def inject(chain: EmulatedChain, clock: HostClock, k: int) -> None:
        if k == cycle:
            action(chain, clock)

    return inject


def every(
    action: Callable[[EmulatedChain, HostClock], None], period: int
) -> Callable[[EmulatedChain, HostClock, int], None]:
    def inject(chain: EmulatedChain, clock: HostClock, k: int) -> None:
        if k >= FAULT_CYCLE and (k - FAULT_CYCLE) % period == 0:
            action(chain, clock)

    return inject


def _jam(chain: EmulatedChain, clock: HostClock) -> None:
    chain.servo(TARGET).motion = ExternalMotion()  # the shaft stops dead, torque on, no fault


class SilenceAtTorqueOn:
    """A ChainPhysics hook that moves nothing: it silences TARGET the moment its torque comes on
    (a servo lost during connect, right after Torque Enable)."""

    def advance(self, servos: Sequence[VirtualServo], dt_s: float) -> None:
        for servo in servos:
            if servo.servo_id == TARGET and servo.torque_enabled:
                self.chain.silence(servo)

    def __init__(self, chain: EmulatedChain) -> None:
        self.chain = chain


def _wrong_baud(chain: EmulatedChain, clock: HostClock) -> None:
    servo = chain.servo(TARGET)
    other = next(v for v, rate in servo.table.baud_rates.items() if rate != chain.baud)
    servo.poke("baud_rate", other)


def _twin(chain: EmulatedChain, clock: HostClock) -> None:
    chain.add(VirtualServo(chain.servo(TARGET).table, TARGET, baud=chain.baud))


def faults(quick: bool = False) -> list[Fault]:
    """Every fault mode at its rates; ``quick`` keeps one rate per mode."""
    drop_rates = (0.02,) if quick else (0.001, 0.01, 0.05, 0.2)
    corrupt_rates = (0.02,) if quick else (0.001, 0.01, 0.05, 0.2)
    out = [
        Fault("none", "", lambda c, h, k: None),
        Fault("silence_at_torque_on", "connect", lambda c, h, k: None, unreachable=(TARGET,)),
    ]
    for p in drop_rates:
        out.append(
            Fault(
                "drop",
                f"p={p}",
                at_cycle(
                    lambda c, h, p=p: [c.drop_replies(s.servo_id, probability=p) for s in c.servos]
                ),
            )
        )
    for p in corrupt_rates:
        out.append(
            Fault(
                "corrupt",
                f"p={p}",
                at_cycle(
                    lambda c, h, p=p: [
                        c.corrupt_replies(s.servo_id, probability=p) for s in c.servos
                    ]
                ),
            )
        )
    for delay in (0.05,) if quick else (0.002, 0.02, 0.05):
        # 50 ms is past the SDK's ~34 ms timeout: the servo looks silent.
        out.append(
            Fault(
                "delay",
                f"{delay * 1000:g}ms",
                at_cycle(lambda c, h, d=delay: c.delay_replies(TARGET, d)),
            )
        )
    out.append(
        Fault("silence", "", at_cycle(lambda c, h: c.silence(TARGET)), unreachable=(TARGET,))
    )
    out.append(Fault("wrong_baud", "", at_cycle(_wrong_baud), unreachable=(TARGET,)))
    for bits, level in (
        (HardwareError.OVERLOAD, "overload"),
        (HardwareError.OVERHEATING, "overheating"),
    ):
        if quick and level != "overload":
            continue
        out.append(
            Fault(
                "hardware_error",
                level,
                at_cycle(lambda c, h, b=bits: c.latch_hardware_error(TARGET, b)),
                torque_cut=(TARGET,),
            )
        )
    for period in (25,) if quick else (1000, 60, 25):  # once, now and then, again and again
        out.append(
            Fault(
                "watchdog_trip",
                f"every {period} cycles",
                every(lambda c, h: h.stall_unseen(0.15), period),
            )
        )
    out.append(Fault("jam", "", at_cycle(_jam)))
    if not quick:
        out.append(
            Fault(
                "reboot", "", at_cycle(lambda c, h: c.servo(TARGET).reboot()), torque_cut=(TARGET,)
            )
        )
        out.append(Fault("duplicate_id", "", at_cycle(_twin), unreachable=(TARGET,)))
    return out


class GoalAudit:
    """Decodes the host's instruction bytes (in the robot's protocol, with the emulator's codec
    for framing only) and checks every Goal Position against joint limits."""

    def __init__(self, robot: RobotConfig, table: ServoTable) -> None:
        converter = TickConverter.for_robot(robot)
        self.limits = {
            servo_id: (int(lo), int(hi))
            for servo_id, lo, hi in zip(
                robot.servo_ids, converter.lower_ticks, converter.upper_ticks, strict=True
            )
        }
        family = family_for(table, robot.bus.protocol)
        # Feetech frames its packets as Protocol 1.0 does (one-byte addresses and lengths).
        self.p1 = family.framing == "dynamixel-1.0"
        self.parser: Any = (protocol1 if self.p1 else protocol2).StreamParser(stale_after_s=None)
        self.register = table["goal_position"]
        self.goal, self.size = self.register.address, self.register.size
        self.big_endian = family.byte_order == "big"  # Feetech SCS words
        self.address_bytes = 1 if self.p1 else 2
        self.sync_write = protocol2.Instruction.SYNC_WRITE  # 0x83 in both protocols
        self.write = protocol2.Instruction.WRITE
        self.goals = 0
        self.out_of_limits: list[tuple[int, int]] = []

    def _value(self, data: bytes) -> int:
        """The goal as the servo reads it: the model data's decoding (two's complement or
        sign-magnitude) of the word in the family's byte order."""
        return self.register.decode(data[::-1] if self.big_endian else data)

    def feed(self, data: bytes) -> None:
        fmt = "<BB" if self.p1 else "<HH"
        head = 2 * self.address_bytes
        for packet in self.parser.feed(data):
            params = packet.params
            if packet.instruction == self.sync_write and len(params) >= head:
                address, size = struct.unpack_from(fmt, params)
                if address == self.goal and size == self.size:
                    for at in range(head, len(params) - size, size + 1):
                        self._check(params[at], self._value(params[at + 1 : at + 1 + size]))
            elif (
                packet.instruction == self.write
                and len(params) == self.address_bytes + self.size
                and int.from_bytes(params[: self.address_bytes], "little") == self.goal
            ):
                self._check(packet.servo_id, self._value(params[self.address_bytes :]))

    def _check(self, servo_id: int, ticks: int) -> None:
        self.goals += 1
        low, high = self.limits.get(servo_id, (0, -1))
        if not low <= ticks <= high:
            self.out_of_limits.append((servo_id, ticks))


GOAL_TURNS_TORQUE_ON = frozenset({"feetech"})
"""Vendors whose servos turn their torque on at a Goal Position write (the emulator's Feetech
firmware, after FTServo_Python's examples, which never write Torque Enable)."""
PORT_HANDLERS: dict[str, type[Any]] = {
    "dynamixel": EmulatedPortHandler,
    "feetech": EmulatedScsPortHandler,
}
"""The emulator's port handler for each vendor's SDK (both open ``dxlemu://`` URLs)."""


def audited_port(audit: GoalAudit, vendor: str = "dynamixel") -> Callable[[str], Any]:
    """The vendor SDK's emulated port handler, feeding every packet the host sends to ``audit``."""

    class AuditedPortHandler(PORT_HANDLERS[vendor]):  # type: ignore[misc]
        def writePort(self, packet: Any) -> int:  # noqa: N802 - the SDK's name
            audit.feed(bytes(packet))
            return int(super().writePort(packet))

    return AuditedPortHandler


@dataclass
class CaseResult:
    """What one (fault, policy) run gave."""

    fault: str
    policy: str
    outcome: str  # "completed", the typed error's class name, or "UNTYPED <class>"
    message: str
    goals: int
    out_of_limits: int
    final_mismatches: list[str] = field(default_factory=list)
    watchdog_trips: int = 0

    @property
    def untyped(self) -> bool:
        return self.outcome.startswith("UNTYPED")

    @property
    def ok(self) -> bool:
        return not (self.untyped or self.out_of_limits or self.final_mismatches)


def with_policy(name: str, policy: str, ramp_s: float) -> RobotConfig:
    base = load_robot(name)
    return dataclasses.replace(
        base, safety=dataclasses.replace(base.safety, stop_policy=policy, ramp_s=ramp_s)
    )


def run_case(
    fault: Fault, policy: str, duration_s: float = 2.0, seed: int = 0, robot_name: str = "snake12"
) -> CaseResult:
    """One run of the robot with ``fault``; see the module docstring for what is checked."""
    robot = with_policy(robot_name, policy, ramp_s=0.3)
    chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud=robot.bus.baud, seed=seed)
    table = chain.servos[0].table
    if fault.mode == "reboot" and table.family in GOAL_TURNS_TORQUE_ON:
        # Nothing is latched: the restarted servo takes the next goal, torque and all, and
        # ends as the policy says like the others.
        fault = dataclasses.replace(fault, torque_cut=())
    version = family_for(table, robot.bus.protocol).protocol
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
        if "protocol_type" in table:
            servo.poke("protocol_type", int(version))
    audit = GoalAudit(robot, table)
    clock = HostClock(chain)
    if fault.mode == "silence_at_torque_on":
        chain.physics = SilenceAtTorqueOn(chain)
    outcome, message = "completed", ""
    trips = 0
    with registered(chain) as url:
        backend = ServoChainBackend(
            robot,
            port=url,
            port_handler_factory=audited_port(audit, table.family),
            clock=clock,
            sleep=chain.advance,
        )
        metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                with backend:
                    run_gait(
                        backend,
                        make_gait("sidewinding", robot.joint_count),
                        SafetyLayer.for_robot(robot),
                        RunPlan(duration_s=duration_s),
                        metrics,
                        on_cycle=lambda k, t: fault.inject(chain, clock, k),
                    )
        except SnakebotError as exc:
            outcome, message = type(exc).__name__, str(exc)
        except Exception as exc:
            outcome, message = f"UNTYPED {type(exc).__name__}", repr(exc)
        trips = int(backend.stats.extra.get("watchdog_trips", 0))
    chain.physics = None
    chain.clear_faults()
    chain.advance(1.0)  # nobody on the bus: an armed watchdog would trip now
    safe = dict(
        zip(
            robot.servo_ids,
            (
                int(t)
                for t in TickConverter.for_robot(robot).to_ticks(
                    SafetyLayer.for_robot(robot).rest_rad
                )
            ),
            strict=True,
        )
    )
    mismatches = final_mismatches(
        chain,
        policy,
        fault,
        started=audit.goals > robot.joint_count,
        safe_ticks=safe,
        watchdog=family_for(table, robot.bus.protocol).capabilities(table).bus_watchdog,
    )
    return CaseResult(
        fault.name,
        policy,
        outcome,
        message,
        audit.goals,
        len(audit.out_of_limits),
        mismatches,
        trips,
    )


def final_mismatches(
    chain: EmulatedChain,
    policy: str,
    fault: Fault,
    started: bool = True,
    safe_ticks: dict[int, int] | None = None,
    watchdog: bool = True,
) -> list[str]:
    """Servos whose final state is not what the stop policy (or their firmware) says; with hold,
    after a run that got going (``started``), that includes the safe pose (Goal Position at
    ``safe_ticks``, by servo ID). ``watchdog``: whether the servos have a Bus Watchdog."""
    out = []
    seen: set[int] = set()
    for servo in chain.servos:
        servo_id = servo.servo_id
        if servo_id in fault.unreachable or servo_id in seen:
            continue
        seen.add(servo_id)
        torque = servo.torque_enabled
        if servo_id in fault.torque_cut:
            if torque:
                out.append(f"servo {servo_id}: torque on after its firmware cut it")
            continue
        if torque != (policy == "hold"):
            out.append(f"servo {servo_id}: torque {'on' if torque else 'off'} with {policy}")
        safe = (safe_ticks or {}).get(servo_id, 2048)
        if servo.watchdog_tripped:
            out.append(f"servo {servo_id}: Bus Watchdog tripped after the stop")
        elif torque and watchdog and servo.peek("bus_watchdog") != 0:
            out.append(f"servo {servo_id}: Bus Watchdog left armed")
        elif torque and started and abs(servo.peek("goal_position") - safe) > 2:
            out.append(
                f"servo {servo_id}: holds goal {servo.peek('goal_position')}, not the safe pose"
            )
    return out


def run_matrix(
    fault_list: Sequence[Fault],
    policies: Sequence[str] = ("hold", "limp"),
    duration_s: float = 2.0,
    robot_name: str = "snake12",
) -> list[CaseResult]:
    """Every fault under every policy."""
    return [run_case(f, p, duration_s, robot_name=robot_name) for f in fault_list for p in policies]


def totals(results: Sequence[CaseResult]) -> dict[str, int]:
    """The must-be-zero figures and the counts around them."""
    return {
        "cases": len(results),
        "completed": sum(r.outcome == "completed" for r in results),
        "typed_errors": sum(not r.untyped and r.outcome != "completed" for r in results),
        "untyped_errors": sum(r.untyped for r in results),
        "goals_audited": sum(r.goals for r in results),
        "out_of_limit_goals": sum(r.out_of_limits for r in results),
        "final_state_mismatches": sum(len(r.final_mismatches) for r in results),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--robot",
        default="snake12",
        help="robot name or file (default snake12; snake12-ax12a: Protocol 1.0)",
    )
    parser.add_argument("--quick", action="store_true", help="one rate per fault mode")
    parser.add_argument("--duration", type=float, default=2.0, help="gait seconds per case")
    parser.add_argument("--json", action="store_true", help="one JSON object on stdout")
    parser.add_argument("--verbose", action="store_true", help="show the backend's warnings")
    args = parser.parse_args()
    if not args.verbose:
        logging.getLogger("snakebot").setLevel(logging.ERROR)
    started = time.perf_counter()
    results = run_matrix(faults(args.quick), duration_s=args.duration, robot_name=args.robot)
    summary = totals(results)
    summary["wall_s"] = round(time.perf_counter() - started, 1)
    bad = summary["untyped_errors"] + summary["out_of_limit_goals"]
    bad += summary["final_state_mismatches"]
    if args.json:
        print(json.dumps({"totals": summary, "cases": [dataclasses.asdict(r) for r in results]}))
        return 1 if bad else 0
    print("| fault | policy | outcome | goals | out of limits | final state | watchdog trips |")
    print("|---|---|---|---|---|---|---|")
    for r in results:
        state = "; ".join(r.final_mismatches) or "as the policy says"
        print(
            f"| {r.fault} | {r.policy} | {r.outcome} | {r.goals} | {r.out_of_limits} | "
            f"{state} | {r.watchdog_trips} |"
        )
    print()
    print(", ".join(f"{k} {v}" for k, v in summary.items()))
    for r in results:
        if r.untyped:
            print(f"UNTYPED in {r.fault}/{r.policy}: {r.message}", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
