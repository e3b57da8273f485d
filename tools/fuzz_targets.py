"""Ways into an emulated chain for tools/fuzz_emulator.py: in-process, and over a real pty.

Both start from the same three servos (IDs 1-3, return delay 0): XL430s for Protocol 2.0; for
Protocol 1.0 two AX-12As and an XL430 with Protocol Type 1 (the two P1 control tables); for
Feetech (`FEETECH`, the SDK's protocol_end 0 of the STS) two STS3215s and an SCS0009 (both byte
orders), probed through the stock `scservo_sdk` over the pty. The pty
target runs the chain and its `PtyServer` in a child process, as `snakebot emulate` does, and
probes it through the unmodified SDK; the child says an input was taken in once its parser has
counted the bytes and no reply is left in flight, and sends the control tables back over a pipe.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.connection import Connection
from typing import Any, Protocol

import fuzz_packets1
from fuzz_packets import packet

from snakebot.emulation import EmulatedChain, VirtualServo

MODEL, MODEL_NUMBER, IDS = "XL430-W250", 1060, (1, 2, 3)
P1_MODELS = {1: ("AX-12A", 12), 2: ("AX-12A", 12), 3: ("XL430-W250", 1060)}
FEETECH = 0
"""The `protocol` value of the Feetech campaign."""
FEETECH_MODELS = {1: ("STS3215", 777), 2: ("STS3215", 777), 3: ("SCS0009", 1284)}
FEETECH_BIG_ENDIAN = frozenset({3})
"""IDs of the SCS servos, whose words are big-endian."""
HANG_S = 1.0
"""CPU time the emulator may spend on one input before it counts as hung."""
STALL_S = 30.0
"""Wall time without an answer that counts as hung whatever the CPU did (a starved emulator on
a loaded machine is slow, not hung, so wall time alone is judged far more leniently)."""


class HangError(Exception):
    """The chain spent over HANG_S of CPU on an input, or answered nothing for STALL_S."""


class CrashError(Exception):
    """The chain raised, or the pty server thread died (the text says how)."""


@dataclass(frozen=True)
class Tables:
    """Every servo's control-table bytes and (ID, secondary ID), in chain order."""

    memory: tuple[bytes, ...]
    identities: tuple[tuple[int, int | None], ...]


def model_number(servo_id: int, protocol: int) -> int:
    """The Model Number the servo with `servo_id` reports."""
    if protocol == FEETECH:
        return FEETECH_MODELS[servo_id][1]
    return MODEL_NUMBER if protocol == 2 else P1_MODELS[servo_id][1]


def make_servos(baud: int, protocol: int = 2) -> list[VirtualServo]:
    """The three servos every input starts from (return delay 0, so the pty runs fast)."""
    servos = []
    for serial, servo_id in enumerate(IDS, start=1):
        models = FEETECH_MODELS if protocol == FEETECH else P1_MODELS
        model = MODEL if protocol == 2 else models[servo_id][0]
        servo = VirtualServo(model, servo_id, baud=baud, processing_time_s=20e-6 + 4e-6 * serial)
        servo.poke("return_delay_time", 0)
        if protocol == 1 and servo.memory.has("protocol_type"):
            servo.poke("protocol_type", 1)
        servos.append(servo)
    return servos


def received(chain: EmulatedChain, protocol: int) -> int:
    """Bytes the chain's receiver for `protocol` has taken in."""
    stats = chain.parser_stats if protocol == 2 else chain.parser1_stats
    return stats.received_bytes


def tables(chain: EmulatedChain) -> Tables:
    """The chain's state as the campaign compares it."""
    with chain.lock:
        servos = chain.servos
        return Tables(
            tuple(bytes(s.memory.data) for s in servos),
            tuple((s.servo_id, s.secondary_id) for s in servos),
        )


def restore(chain: EmulatedChain, protocol: int) -> None:
    """Fresh servos in place of the fuzzed ones (same chain, so the transport stays)."""
    with chain.lock:
        for servo in chain.servos:
            chain.remove(servo)
        for servo in make_servos(chain.baud, protocol):
            chain.add(servo)


class Target(Protocol):
    """A way into a chain (see the module docstring)."""

    def tables(self) -> Tables:
        """The state before an input."""

    def send(self, data: bytes) -> tuple[list[bytes] | None, Tables]:
        """Feed `data`; its replies (None where they are not seen) and the state after.
        Raises HangError or CrashError."""

    def restore(self) -> None:
        """Put fresh servos back."""

    def probe(self, servo_id: int) -> None:
        """Ping `servo_id` and read its Model Number; AssertionError if either is wrong,
        HangError if no answer comes within HANG_S."""

    def restart(self) -> None:
        """Start over after a crash or hang."""

    def close(self) -> None:
        """Release what the target holds."""


class InProcess:
    """Bytes straight into `EmulatedChain.receive`; the replies are seen."""

    BAUD = 1_000_000

    def __init__(self, protocol: int = 2) -> None:
        self.protocol = protocol
        self.restart()

    def restart(self) -> None:
        self.chain = EmulatedChain(make_servos(self.BAUD, self.protocol), baud=self.BAUD)
        self._probes = {}
        for servo, servo_id in zip(self.chain.servos, IDS, strict=True):
            order = (
                "big" if self.protocol == FEETECH and servo_id in FEETECH_BIG_ENDIAN else "little"
            )
            model = model_number(servo_id, self.protocol).to_bytes(2, order)
            if self.protocol == FEETECH:  # Model Number at 3, after ID-free ping status
                p1 = fuzz_packets1.packet
                self._probes[servo_id] = [
                    (p1(servo_id, 0x01, b""), p1(servo_id, 0x00, b"")),
                    (p1(servo_id, 0x02, b"\x03\x02"), p1(servo_id, 0x00, model)),
                ]
                continue
            if self.protocol == 1:  # status = an instruction packet with the error byte
                p1 = fuzz_packets1.packet
                self._probes[servo_id] = [
                    (p1(servo_id, 0x01, b""), p1(servo_id, 0x00, b"")),
                    (p1(servo_id, 0x02, b"\x00\x02"), p1(servo_id, 0x00, model)),
                ]
                continue
            firmware = servo.peek("firmware_version")
            self._probes[servo_id] = [
                (
                    packet(servo_id, 0x01, b""),
                    packet(servo_id, 0x55, b"\x00" + model + bytes([firmware])),
                ),
                (
                    packet(servo_id, 0x02, b"\x00\x00\x02\x00"),
                    packet(servo_id, 0x55, b"\x00" + model),
                ),
            ]

    def tables(self) -> Tables:
        return tables(self.chain)

    def send(self, data: bytes) -> tuple[list[bytes] | None, Tables]:
        began = time.thread_time()
        try:
            replies = [reply.data for reply in self.chain.receive(data)]
        except Exception as exc:
            raise CrashError(traceback.format_exc()) from exc
        if time.thread_time() - began > HANG_S:
            raise HangError(f"{time.thread_time() - began:.1f} s of CPU for {len(data)} bytes")
        return replies, tables(self.chain)

    def restore(self) -> None:
        restore(self.chain, self.protocol)

    def probe(self, servo_id: int) -> None:
        for question, answer in self._probes[servo_id]:
            got = b"".join(r.data for r in self.chain.receive(question))
            assert got == answer, f"ID {servo_id}: {question.hex(' ')} got {got.hex(' ')}"

    def close(self) -> None:
        pass


def _serve(conn: Connection, baud: int, protocol: int) -> None:
    """The child process: a chain on a PtyServer, and commands from the campaign on `conn`."""
    from snakebot.emulation.pty_server import PtyServer

    chain = EmulatedChain(make_servos(baud, protocol), baud=baud)
    server = PtyServer(chain).start()
    conn.send(server.device_path)
    while True:
        command, argument = conn.recv()
        if command == "tables":
            with chain.lock:
                conn.send((received(chain, protocol), tables(chain)))
        elif command == "settle":
            conn.send(_settle(chain, server, argument, protocol))
        elif command == "restore":
            restore(chain, protocol)
            conn.send(None)
        else:
            server.stop()
            conn.send(None)
            return


def _settle(chain: EmulatedChain, server: Any, total: int, protocol: int) -> tuple[str, Any]:
    """Wait until `received` bytes are in and answered; the server thread's CPU time judges."""
    thread = next(t for t in threading.enumerate() if t.name.startswith("pty-server"))
    clock = time.pthread_getcpuclockid(thread.ident or 0)
    cpu, wall = time.clock_gettime(clock), time.monotonic()
    while True:
        with chain.lock:
            if received(chain, protocol) >= total and server.replies_in_flight == 0:
                return "ok", tables(chain)
        if server.failure is not None:
            return "crash", repr(server.failure)
        busy = time.clock_gettime(clock) - cpu
        if busy > HANG_S or time.monotonic() - wall > STALL_S:
            taken = received(chain, protocol)
            return "hang", f"{taken} of {total} bytes taken in; {busy:.2f} s of CPU"
        time.sleep(100e-6)


class OverPty:
    """Bytes written to a pseudo-terminal served by `PtyServer` in a child process; the probes
    run through the unmodified SDK. Replies to fuzz inputs are not seen (the SDK drops them)."""

    BAUD = 1_000_000

    def __init__(self, protocol: int = 2) -> None:
        self.protocol = protocol
        self._start()

    def _start(self) -> None:
        import dynamixel_sdk as dxl

        self._feetech: dict[int, Any] = {}
        if self.protocol == FEETECH:
            import scservo_sdk as sdk

            self._dxl: Any = sdk
        else:
            self._dxl = dxl
        self._conn, child = multiprocessing.get_context("fork").Pipe()
        self._process = multiprocessing.get_context("fork").Process(
            target=_serve, args=(child, self.BAUD, self.protocol), daemon=True
        )
        self._process.start()
        device = self._conn.recv()
        self.port = self._dxl.PortHandler(device)
        if not (self.port.openPort() and self.port.setBaudRate(self.BAUD)):
            raise RuntimeError(f"cannot open {device}")
        if self.protocol == FEETECH:
            sdk = self._dxl
            for servo_id in IDS:
                big = servo_id in FEETECH_BIG_ENDIAN
                self._feetech[servo_id] = (sdk.scscl if big else sdk.sms_sts)(self.port)
        else:
            self.packets = dxl.PacketHandler(float(self.protocol))
        self._received = 0

    def _ask(self, command: str, argument: Any = None) -> Any:
        self._conn.send((command, argument))
        if not self._conn.poll(2 * STALL_S):
            raise HangError(f"the emulator process did not answer {command!r}")
        return self._conn.recv()

    def tables(self) -> Tables:
        self._received, state = self._ask("tables")
        assert isinstance(state, Tables)
        return state

    def send(self, data: bytes) -> tuple[list[bytes] | None, Tables]:
        os.write(self.port.ser.fileno(), data)
        outcome, detail = self._ask("settle", self._received + len(data))
        if outcome == "crash":
            raise CrashError(detail)
        if outcome == "hang":
            raise HangError(detail)
        return None, detail

    def restore(self) -> None:
        self._ask("restore")

    def probe(self, servo_id: int) -> None:
        # A loaded machine can delay an answer past the SDK's ~35 ms timeout: ask again, for up
        # to STALL_S; a wrong answer fails at once. Once a question has timed out, its late
        # answer may arrive while the SDK waits for the next one (which it then misreads: a
        # Protocol 1.0 ping status has no data for the Read after it); only then is a short or
        # wrong answer asked again rather than counted.
        dxl, deadline = self._dxl, time.monotonic() + STALL_S
        timed_out = False
        questions: tuple[Callable[[], tuple[int, int, int]], ...]
        if self.protocol == FEETECH:  # the SDK's ping reads Model Number (3) itself
            feetech = self._feetech[servo_id]
            questions = (
                lambda: feetech.ping(servo_id),
                lambda: feetech.read2ByteTxRx(servo_id, 3),
            )
        else:
            questions = (
                lambda: self.packets.ping(self.port, servo_id),
                lambda: self.packets.read2ByteTxRx(self.port, servo_id, 0),
            )
        for ask in questions:
            while True:
                try:
                    model, result, error = ask()
                except IndexError as exc:  # the SDK indexed a status without data
                    if not timed_out:
                        raise AssertionError(f"ID {servo_id}: a status too short to read") from exc
                    model, result, error = 0, dxl.COMM_RX_CORRUPT, 0
                expected = model_number(servo_id, self.protocol)
                if result == dxl.COMM_SUCCESS and (
                    (model, error) == (expected, 0) or not timed_out
                ):
                    assert (model, error) == (expected, 0), f"ID {servo_id}: {model}, {error}"
                    break
                timed_out = timed_out or result != dxl.COMM_SUCCESS
                if time.monotonic() > deadline:
                    raise HangError(f"ID {servo_id}: no answer (SDK result {result})")

    def restart(self) -> None:
        self.close()
        self._start()

    def close(self) -> None:
        self.port.closePort()
        if self._process.is_alive():
            with contextlib.suppress(EOFError, OSError, HangError):
                self._ask("stop")
            self._process.join(timeout=5)
        if self._process.is_alive():
            self._process.kill()
