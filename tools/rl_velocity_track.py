"""How well a trained SnakeVelocity policy follows the commanded speed, on the twin and over a bus.

For each commanded speed (turn rate 0) it plays the policy as a user would:

  twin   ``snakebot run --policy DIR --command V,0 --duration D --json`` (the twin's own summary)
  bus    ``snakebot emulate --robot R --pty --physics --json`` in one process and
         ``snakebot run --backend dynamixel --port PTY --policy DIR ...`` in another; the speed
         is the emulator's twin's (the bus itself knows no pose), from its exit summary

and reports ``speed_mps`` (straight-line COM displacement / run time, the ramp-in included) per
command, with the slope and correlation of measured against commanded speed.

    python tools/rl_velocity_track.py vel/ [--commands 0.1,0.2,0.3] [--duration 20] [--no-bus]
"""

from __future__ import annotations

import argparse
import json
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np

SNAKEBOT = [sys.executable, "-m", "snakebot"]


def _run(args: list[str], timeout_s: float) -> dict[str, Any]:
    done = subprocess.run([*SNAKEBOT, *args], capture_output=True, text=True, timeout=timeout_s)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(args)}: exit {done.returncode}\n{done.stderr}")
    summary: dict[str, Any] = json.loads(done.stdout)
    return summary


def on_twin(policy: Path, robot: str, speed: float, duration_s: float) -> float:
    """The twin run's speed_mps for ``speed`` m/s commanded."""
    summary = _run(["run", "--robot", robot, "--policy", str(policy), "--command", f"{speed:g},0",
                    "--duration", f"{duration_s:g}", "--json"], timeout_s=20 * duration_s + 120)
    return float(summary["speed_mps"])


def over_bus(policy: Path, robot: str, speed: float, duration_s: float) -> float:
    """The speed_mps of the twin behind an emulated bus the policy drives servo by servo."""
    emulator = subprocess.Popen(
        [*SNAKEBOT, "emulate", "--robot", robot, "--pty", "--physics", "--json"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        assert emulator.stdout is not None
        port = json.loads(emulator.stdout.readline())["port"]
        _run(["run", "--backend", "dynamixel", "--port", port, "--robot", robot, "--policy",
              str(policy), "--command", f"{speed:g},0", "--duration", f"{duration_s:g}",
              "--json"], timeout_s=20 * duration_s + 120)
    finally:
        if emulator.poll() is None:
            emulator.send_signal(signal.SIGINT)
        out, err = emulator.communicate(timeout=60)
    if emulator.returncode != 0:
        raise SystemExit(f"emulate: exit {emulator.returncode}\n{err}")
    lines = [json.loads(line) for line in out.splitlines() if line.strip()]
    return float(lines[-1]["speed_mps"])


def fit(commanded: list[float], measured: list[float]) -> dict[str, float]:
    """Least-squares slope and intercept of measured on commanded speed, and their correlation."""
    x, y = np.asarray(commanded), np.asarray(measured)
    slope, intercept = np.polyfit(x, y, 1)
    return {"slope": float(slope), "intercept_mps": float(intercept),
            "correlation": float(np.corrcoef(x, y)[0, 1])}


def main(argv: list[str] | None = None) -> int:
    """Measure, print a table (or JSON); exit 0."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("policy", type=Path, help="a SnakeVelocity policy folder (rl train --out)")
    parser.add_argument("--robot", default="snake8")
    parser.add_argument("--commands", default="0.1,0.2,0.3", help="speeds in m/s, comma-separated")
    parser.add_argument("--duration", type=float, default=20.0, help="seconds per run")
    parser.add_argument("--no-bus", action="store_true", help="the twin only")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    speeds = [float(v) for v in args.commands.split(",")]
    results: dict[str, Any] = {"commanded_mps": speeds}
    paths = {"twin": on_twin} if args.no_bus else {"twin": on_twin, "bus": over_bus}
    for name, measure in paths.items():
        measured = [measure(args.policy, args.robot, v, args.duration) for v in speeds]
        results[name] = {"speed_mps": measured, **fit(speeds, measured)}
    if args.json:
        print(json.dumps(results, indent=2))
        return 0
    print("commanded m/s  " + "  ".join(f"{name:>8}" for name in paths))
    for i, v in enumerate(speeds):
        print(f"{v:13.2f}  " + "  ".join(f"{results[n]['speed_mps'][i]:8.3f}" for n in paths))
    for name in paths:
        r = results[name]
        print(f"{name}: slope {r['slope']:.2f}, intercept {r['intercept_mps']:.3f} m/s, "
              f"correlation {r['correlation']:.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
