"""`snakebot emulate --pty --json` in a subprocess, as a user runs it, for pty tests."""

from __future__ import annotations

import json
import select
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


class Emulator:
    """A running `snakebot emulate --pty --json`: its port and its event lines."""

    def __init__(self, proc: subprocess.Popen[str]) -> None:
        self.proc = proc
        self.first = self.event()
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
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        yield Emulator(proc)
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            proc.wait(timeout=10)
        assert proc.returncode == 0, proc.stderr.read() if proc.stderr else ""
