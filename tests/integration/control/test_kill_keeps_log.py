"""A run killed with SIGKILL keeps every completed cycle; SIGTERM ramps out first."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from snakebot.telemetry import read_log


def _start(log: Path) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "snakebot",
            "run",
            "--realtime",
            "--duration",
            "60",
            "--log",
            str(log),
            "--json",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )


def _wait_rows(log: Path, rows: int, timeout_s: float = 30.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if log.exists() and log.read_text().count("\n") > rows:
            return
        time.sleep(0.05)
    raise AssertionError(f"{log} never reached {rows} rows")


def test_sigkill_loses_no_completed_cycle(tmp_path: Path) -> None:
    log = tmp_path / "run.csv"
    process = _start(log)
    try:
        _wait_rows(log, 50)
    finally:
        process.kill()
        process.wait()
    data = read_log(log)
    assert data.values.shape[0] >= 50
    np.testing.assert_array_equal(data.column("cycle"), np.arange(data.values.shape[0]))
    assert np.isfinite(data.values[:, :-3]).all()


def test_sigterm_ramps_out_and_exits_130(tmp_path: Path) -> None:
    log = tmp_path / "run.csv"
    process = _start(log)
    _wait_rows(log, 50)
    os.kill(process.pid, signal.SIGTERM)
    out, _ = process.communicate(timeout=30)
    assert process.returncode == 130
    assert b'"interrupted": true' in out
    commands = read_log(log).joints("command_rad")
    assert np.abs(commands[-1]).max() < 1e-6  # ended on the rest pose after the ramp-out
