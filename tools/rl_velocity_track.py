"""How well a trained SnakeVelocity policy follows the commanded speed, on the twin and over a bus.

For each commanded speed (turn rate 0) it plays the policy as a user would:

  twin   ``snakebot run --policy DIR --command V,0 --duration D --json`` (the twin's own summary)
  bus    ``snakebot emulate --robot R --pty --physics --json`` in one process and
         ``snakebot run --backend dynamixel --port PTY --policy DIR ...`` in another; the speed
         is the emulator's twin's (the bus itself knows no pose), from its exit summary

and reports per command ``speed_mps`` (straight-line COM displacement / run time, the ramp-in
included: what the run summary says) and, on the twin, the path speed (the COM's path sampled
once a second from the run's telemetry log, after the first ``SETTLE_S``, over that time: a
policy that turns is not penalised for the curve), with the slope and correlation of measured
against commanded speed and the turn each run made.

    python tools/rl_velocity_track.py vel/ [--commands 0.1,0.2,0.3] [--duration 20] [--no-bus]
"""

from __future__ import annotations

import argparse
import json
import signal
import subprocess
import sys
import tempfile
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


SETTLE_S = 2.0


def path_speed_mps(log: Path, rate_hz: float) -> float:
    """COM path length / time from a run's CSV log, sampled once a second after SETTLE_S."""
    with log.open(encoding="utf-8") as handle:
        header = handle.readline().strip().split(",")
        x, y = header.index("com_x_m"), header.index("com_y_m")
        rows = [line.split(",") for line in handle if line.strip()]
    step = max(1, round(rate_hz))
    points = np.array([[float(r[x]), float(r[y])] for r in rows[round(SETTLE_S * rate_hz) :: step]])
    seconds = (len(points) - 1) * step / rate_hz
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum() / seconds)


def on_twin(policy: Path, robot: str, speed: float, duration_s: float) -> dict[str, float]:
    """The twin run's speed_mps, path speed and turn for ``speed`` m/s commanded."""
    with tempfile.TemporaryDirectory() as folder:
        log = Path(folder) / "run.csv"
        summary = _run(
            [
                "run",
                "--robot",
                robot,
                "--policy",
                str(policy),
                "--command",
                f"{speed:g},0",
                "--duration",
                f"{duration_s:g}",
                "--log",
                str(log),
                "--json",
            ],
            timeout_s=20 * duration_s + 120,
        )
        path = path_speed_mps(log, float(summary["rate_hz"]))
    return {
        "speed_mps": float(summary["speed_mps"]),
        "path_speed_mps": path,
        "turn_deg": float(summary["turn_deg"]),
    }


def over_bus(policy: Path, robot: str, speed: float, duration_s: float) -> dict[str, float]:
    """The speed_mps of the twin behind an emulated bus the policy drives servo by servo."""
    emulator = subprocess.Popen(
        [*SNAKEBOT, "emulate", "--robot", robot, "--pty", "--physics", "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert emulator.stdout is not None
        port = json.loads(emulator.stdout.readline())["port"]
        _run(
            [
                "run",
                "--backend",
                "dynamixel",
                "--port",
                port,
                "--robot",
                robot,
                "--policy",
                str(policy),
                "--command",
                f"{speed:g},0",
                "--duration",
                f"{duration_s:g}",
                "--json",
            ],
            timeout_s=20 * duration_s + 120,
        )
    finally:
        if emulator.poll() is None:
            emulator.send_signal(signal.SIGINT)
        out, err = emulator.communicate(timeout=60)
    if emulator.returncode != 0:
        raise SystemExit(f"emulate: exit {emulator.returncode}\n{err}")
    twin = [json.loads(line) for line in out.splitlines() if line.strip()][-1]
    return {"speed_mps": float(twin["speed_mps"]), "turn_deg": float(twin["turn_deg"])}


def fit(commanded: list[float], measured: list[float]) -> dict[str, float]:
    """Least-squares slope and intercept of measured on commanded speed, and their correlation."""
    x, y = np.asarray(commanded), np.asarray(measured)
    slope, intercept = np.polyfit(x, y, 1)
    return {
        "slope": float(slope),
        "intercept_mps": float(intercept),
        "correlation": float(np.corrcoef(x, y)[0, 1]),
    }


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
        runs = [measure(args.policy, args.robot, v, args.duration) for v in speeds]
        results[name] = {key: [run[key] for run in runs] for key in runs[0]}
        for key in ("speed_mps", "path_speed_mps"):
            if key in results[name]:
                results[name][f"fit_{key}"] = fit(speeds, results[name][key])
    if args.json:
        print(json.dumps(results, indent=2))
        return 0
    for name in paths:
        r = results[name]
        keys = [k for k in ("speed_mps", "path_speed_mps", "turn_deg") if k in r]
        print(f"{name}: commanded m/s  " + "  ".join(f"{k:>14}" for k in keys))
        for i, v in enumerate(speeds):
            print(f"{'':6}{v:13.2f}  " + "  ".join(f"{r[k][i]:14.3f}" for k in keys))
        for key in ("speed_mps", "path_speed_mps"):
            if f"fit_{key}" in r:
                f = r[f"fit_{key}"]
                print(
                    f"{'':6}{key}: slope {f['slope']:.2f}, intercept {f['intercept_mps']:.3f} "
                    f"m/s, correlation {f['correlation']:.3f}"
                )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
