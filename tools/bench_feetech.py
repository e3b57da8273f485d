"""Control-cycle cost of the chain backend on 12 Feetech STS3215 servos against a bare
scservo_sdk loop, and the control rate the bus holds at 1 Mbps with SYNC_READ (issue 22).

One cycle = what ``snakebot run`` does each control period on snake12-sts3215: one SYNC_WRITE of
12 Goal Positions (42, 2 bytes) and one SYNC_READ of the state block the backend reads (Present
Position 56 .. Present Current 69: 15 bytes), decoded to SI. The bare side is the same cycle as a
careful user writes it with Feetech's SDK (``sms_sts`` packet handler, ``GroupSyncWrite`` with
``changeParam``, ``GroupSyncRead`` built once, ``getData`` and the SDK's ``scs_tohost`` for the
sign-magnitude words). Both talk through scservo_sdk and the emulator's ``EmulatedScsPortHandler``
to identical in-process emulated chains (``dxlemu://``, virtual time: no wire time is waited),
alternating cycle by cycle (tools/bench_dynamixel_cycle.py's harness); "client" is the cycle
minus the time inside the emulated port: the host CPU a real bus would see.

The rate is the bus's arithmetic (snakebot.backends.chain.rate, what ``snakebot run``
refuses a ``--rate`` with) plus the measured host CPU: the wire at 10 bits a byte, one Return
Delay Time per reply, 1 ms of USB latency per cycle (one reply wait).

Usage: python tools/bench_feetech.py [--rounds 9] [--cycles 300]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import platform
import warnings

import numpy as np
import scservo_sdk as scs
from bench_dynamixel_cycle import EmulatorClock, Side, measure, med

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.backends.chain.rate import cycle_budget
from snakebot.config import load_robot
from snakebot.config.schema import RobotConfig
from snakebot.emulation import EmulatedChain, make_chain_for_ids, register_chain
from snakebot.emulation.port_feetech import EmulatedScsPortHandler
from snakebot.families import family_named
from snakebot.servo_tables import table_for_model
from snakebot.types import JointCommand

ROBOT, MODEL, N, BAUD = "snake12-sts3215", "STS3215", 12, 1_000_000
GOAL, STATE, STATE_LENGTH = 42, 56, 15  # Goal Position; Present Position .. Present Current
POSITION, SPEED, CURRENT = 56, 58, 69


def robot() -> RobotConfig:
    """The shipped snake, no ramp."""
    base = load_robot(ROBOT)
    return dataclasses.replace(base, safety=dataclasses.replace(base.safety, ramp_s=0.0))


def chain() -> EmulatedChain:
    servos = make_chain_for_ids(MODEL, range(1, N + 1), BAUD)
    for servo in servos.servos:
        servo.poke("return_delay_time", 0)  # as `config apply` leaves them
    return servos


class BareLoop:
    """The cycle written with scservo_sdk by hand: groups built once, getData decoding."""

    def __init__(self, url: str) -> None:
        table = table_for_model(MODEL)
        self.rad_per_tick = table["present_position"].scale
        self.rad_s_per_unit = table["present_velocity"].scale
        self.amp_per_unit = table["present_current"].scale
        self.ids = list(range(1, N + 1))
        self.port = EmulatedScsPortHandler(url)
        self.port.setBaudRate(BAUD)
        self.packet = scs.sms_sts(self.port)
        self.writer = scs.GroupSyncWrite(self.packet, GOAL, 2)
        self.reader = scs.GroupSyncRead(self.packet, STATE, STATE_LENGTH)
        for servo_id in self.ids:
            self.writer.addParam(servo_id, [0, 8])
            self.reader.addParam(servo_id)
            self.packet.write1ByteTxRx(servo_id, 40, 1)

    def cycle(self, goal_rad: list[float]) -> tuple[list[float], list[float], list[float]]:
        ph = self.packet
        for servo_id, angle in zip(self.ids, goal_rad, strict=True):
            ticks = ph.scs_toscs(round(2048 + angle / self.rad_per_tick), 15)
            self.writer.changeParam(servo_id, [ph.scs_lobyte(ticks), ph.scs_hibyte(ticks)])
        if self.writer.txPacket() != scs.COMM_SUCCESS:
            raise RuntimeError("sync write failed")
        if self.reader.txRxPacket() != scs.COMM_SUCCESS:
            raise RuntimeError("sync read failed")
        position, velocity, current = [], [], []
        for servo_id in self.ids:
            ok, _ = self.reader.isAvailable(servo_id, STATE, STATE_LENGTH)
            if not ok:
                raise RuntimeError(f"servo {servo_id} missing from the sync read")
            pos = ph.scs_tohost(self.reader.getData(servo_id, POSITION, 2), 15)
            vel = ph.scs_tohost(self.reader.getData(servo_id, SPEED, 2), 15)
            amp = self.reader.getData(servo_id, CURRENT, 2)
            position.append((pos - 2048) * self.rad_per_tick)
            velocity.append(vel * self.rad_s_per_unit)
            current.append(amp * self.amp_per_unit)
        return position, velocity, current


def make_sides(cycles: int) -> dict[str, Side]:
    handlers: list[EmulatedScsPortHandler] = []

    def factory(name: str) -> EmulatedScsPortHandler:
        handlers.append(EmulatedScsPortHandler(name))
        return handlers[-1]

    ours = chain()
    backend = ServoChainBackend(
        robot(),
        port=register_chain(ours),
        baud=BAUD,
        port_handler_factory=factory,
        slow_every=10**9,  # only the cycle's two transactions
        clock=lambda: ours.now_s,
        sleep=ours.advance,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        backend.connect()
    assert backend.bus.capabilities.read_method == "sync_read"
    assert backend.rate_budget().method == "sync_read"
    bare = BareLoop(register_chain(chain()))
    clocks = {"backend": EmulatorClock(), "bare": EmulatorClock()}
    clocks["backend"].instrument(handlers[0])  # type: ignore[arg-type]
    clocks["bare"].instrument(bare.port)  # type: ignore[arg-type]
    t = np.arange(cycles) * 0.005
    waves = [0.5 * np.sin(2 * math.pi * 1.0 * tk - 0.6 * np.arange(N)) for tk in t]

    def run_backend(command: JointCommand) -> None:
        backend.send_command(command)
        backend.read_state()

    return {
        "backend": Side(run_backend, [JointCommand(w) for w in waves], clocks["backend"]),
        "bare": Side(bare.cycle, [w.tolist() for w in waves], clocks["bare"]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=9)
    parser.add_argument("--cycles", type=int, default=300)
    args = parser.parse_args()
    results = measure({"sts": make_sides(args.cycles)}, args.rounds, args.cycles)["sts"]
    family = family_named("feetech-sts")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"Python {platform.python_version()}, {os.cpu_count()} CPUs, load {load:.1f}, "
        f"{args.rounds} rounds x {args.cycles} cycles per side, {N} x {MODEL} at {BAUD} bit/s, "
        f"SYNC_WRITE of 2 B + SYNC_READ of {STATE_LENGTH} B."
    )
    host_s = med(results["backend_client"], 1)
    print(
        "\n| | bare scservo_sdk loop | chain backend |\n|---|---|---|\n"
        f"| host CPU per cycle (client), µs | {med(results['bare_client']):.0f} "
        f"| {med(results['backend_client']):.0f} |\n"
        f"| whole cycle on the emulator, µs | {med(results['bare_whole']):.0f} "
        f"| {med(results['backend_whole']):.0f} |\n"
    )
    print(
        f"ratio client {med(results['ratio_client'], 1):.2f} "
        f"({min(results['ratio_client']):.2f}–{max(results['ratio_client']):.2f}), "
        f"ratio whole cycle {med(results['ratio_whole'], 1):.2f} "
        f"({min(results['ratio_whole']):.2f}–{max(results['ratio_whole']):.2f})\n"
    )
    print(
        "| Return Delay Time | wire µs | bus cycle µs | rate with the host CPU |\n|---|---|---|---|"
    )
    for label, delay_s in (("0 (the servo file's)", 0.0), ("250 = 500 µs (factory)", 500e-6)):
        budget = cycle_budget(family, "sync_read", N, STATE_LENGTH, 2, BAUD, delay_s)
        print(
            f"| {label} | {budget.wire_s * 1e6:.0f} | {budget.cycle_s * 1e6:.0f} "
            f"| {1.0 / (budget.cycle_s + host_s):.0f} Hz |"
        )


if __name__ == "__main__":
    main()
