"""`snakebot emulate --pty --json` in a subprocess, as a user runs it, for pty tests; and
`patient`, for asking the bus again when a loaded machine delays its answer."""

from __future__ import annotations

import json
import select
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar


class Emulator:
    """A running `snakebot emulate --pty --json`: its port and its event lines."""

    def __init__(self, proc: subprocess.Popen[str]) -> None:
        self.proc = proc
        # Start-up imports MuJoCo and builds the chain: tens of seconds on a loaded machine.
        self.first = self.event(timeout_s=90.0)
        self.port = str(self.first["port"])

    def event(self, timeout_s: float = 20.0) -> dict[str, Any]:
        assert self.proc.stdout is not None
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout_s)
        assert ready, "the emulator printed nothing"
        payload: dict[str, Any] = json.loads(self.proc.stdout.readline())
        return payload

    def stop(self) -> list[dict[str, Any]]:
        """SIGINT, as Ctrl-C; wait for a clean exit; the JSON lines it printed on the way out."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
        out, err = self.proc.communicate(timeout=30)
        assert self.proc.returncode == 0, err
        return [json.loads(line) for line in out.splitlines() if line.strip()]

    def command(self, line: str) -> dict[str, Any]:
        assert self.proc.stdin is not None
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        return self.event()


@contextmanager
def emulator(*args: str) -> Iterator[Emulator]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "snakebot", "emulate", "--pty", "--json", *args],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        yield Emulator(proc)
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            proc.wait(timeout=30)
        assert proc.returncode == 0, proc.stderr.read() if proc.stderr else ""


T = TypeVar("T")


def patient(transaction: Callable[[], T], seconds: float = 10.0) -> T:
    """Run an SDK transaction again while it times out or comes back garbled, for `seconds`.

    The emulator is a process like any other: on a loaded machine it can miss the SDK's ~35 ms
    timeout. Tests that check what the bus says (not when) ask again; any other outcome is
    returned at once, and an emulator that never answers still fails the test. `transaction`
    returns what the SDK does: a result code, (result, error) or (value, result, error).
    """
    import dynamixel_sdk as dxl

    deadline = time.monotonic() + seconds
    while True:
        outcome = transaction()
        if isinstance(outcome, int):
            result = outcome
        else:
            assert isinstance(outcome, tuple)
            result = outcome[0] if len(outcome) == 2 else outcome[1]
        if result not in (dxl.COMM_RX_TIMEOUT, dxl.COMM_RX_CORRUPT) or time.monotonic() > deadline:
            return outcome
