"""The loop-cost benchmarks run, and their bare replays are the runs' own physics.

Speed is never asserted here (docs/benchmarks.md has the figures and how they were taken); what
is asserted is what makes those figures mean something: each tool runs on today's code (a tool
that crashed with KeyError for weeks went unnoticed without this), and each bare replay ends in
the run's state bit for bit, so ``snakebot / replay`` compares the same physics.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

TOOLS = Path(__file__).resolve().parents[3] / "tools"


def bench(name: str, *argv: str) -> str:
    done = subprocess.run(
        [sys.executable, str(TOOLS / name), *argv], capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def test_the_twin_benchmark_replays_the_runs_physics_bit_for_bit() -> None:
    out = bench("bench_twin.py", "--sizes", "8", "--rounds", "1", "--seconds", "0.5")
    assert "the bare replay ends 0 from the run's state" in out
    assert re.search(r"^\| 8 \| [\d,]+ \|", out, re.MULTILINE), out


def test_the_cycle_benchmark_times_the_real_twin_cycle() -> None:
    out = bench("bench_cycle.py", "--repeats", "1", "--seconds", "0.5")
    physics = re.search(r"mj_step (\d+) us/cycle", out)
    assert physics is not None and int(physics.group(1)) > 0, out
    assert "| health |" in out and "| sum of stages |" in out


def test_the_soft_body_benchmark_replays_the_runs_physics_bit_for_bit() -> None:
    out = bench("bench_softbody.py", "--sizes", "6", "--rounds", "1", "--seconds", "0.5")
    assert "the replay ends 0 from the run's state" in out


def test_the_rl_benchmark_replays_the_envs_physics_bit_for_bit() -> None:
    pytest.importorskip("gymnasium")
    # 320 steps: past the first episode's 300, so a reset starts a second stretch.
    out = bench(
        "bench_rl.py", "--rounds", "1", "--steps", "320", "--skip-ppo", "--encodings", "dft"
    )
    assert "largest difference 0 (0 = the same physics)" in out
