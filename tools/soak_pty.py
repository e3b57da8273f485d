"""Wall-clock soak: `snakebot run --backend dynamixel` against `snakebot emulate --pty --physics`.

Both run as the user runs them, each in its own process, for `--duration` seconds of real time,
while `--load` CPU-bound processes compete for the cores. The soak passes when:

- the run exits 0, not interrupted, and its telemetry has one row per control cycle, in order;
- the achieved control rate is at least `--min-rate-fraction` of the requested one;
- the emulator saw no damaged or stale bytes (its parser dropped nothing) and no Bus Watchdog
  fired on any servo (its exit summary says so);
- the emulator's resident memory grew by at most `--max-growth-mib` between the end of the first
  fifth of the run and the end (sampled once a second from /proc).

The report also gives `longest_cpu_wait_s`: the longest the emulator or the run waited, runnable,
for a CPU within a tenth of a second (/proc/<pid>/task/<tid>/schedstat). A machine that starves
them for 0.1 s or more breaks any 100 ms watchdog or 35 ms timeout whatever the code does.

Usage: python tools/soak_pty.py [--duration 60] [--rate 50] [--load 2] [--json]
Prints a JSON report with --json; exits 1 if any check fails.
"""

from __future__ import annotations

import argparse
import csv
import json
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

PYTHON = sys.executable
BURN = "while True:\n    pass\n"


def rss_mib(pid: int) -> float | None:
    """Resident memory of `pid` in MiB (None once it is gone)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


def run_queue_s(pid: int) -> dict[int, float]:
    """Seconds each thread of `pid` has waited, runnable, for a CPU (/proc/.../schedstat)."""
    waits = {}
    try:
        for task in Path(f"/proc/{pid}/task").iterdir():
            waits[int(task.name)] = int((task / "schedstat").read_text().split()[1]) / 1e9
    except (OSError, ValueError, IndexError):
        pass
    return waits


class Sampler(threading.Thread):
    """Samples the emulator's resident memory once a second ((seconds since start, MiB)) and,
    ten times a second, the longest any thread of `pids` waited runnable for a CPU."""

    def __init__(self, pid: int) -> None:
        super().__init__(daemon=True)
        self.pid = pid
        self.pids = [pid]
        self.samples: list[tuple[float, float]] = []
        self.starved_s = 0.0
        self.done = threading.Event()

    def run(self) -> None:
        start = next_rss = sampled = time.monotonic()
        last: dict[tuple[int, int], float] = {}
        while not self.done.wait(0.1):
            now = time.monotonic()
            interval, sampled = now - sampled, now
            for pid in list(self.pids):
                for tid, waited in run_queue_s(pid).items():
                    before = last.get((pid, tid))
                    # Count a wait only if it filled half the interval (this sampler can be
                    # late too): then it was one stretch of about that length.
                    if before is not None and waited - before >= 0.5 * interval:
                        self.starved_s = max(self.starved_s, waited - before)
                    last[(pid, tid)] = waited
            if time.monotonic() >= next_rss:
                next_rss += 1.0
                value = rss_mib(self.pid)
                if value is not None:
                    self.samples.append((time.monotonic() - start, value))


def read_json_line(stream: Any, timeout_s: float) -> dict[str, Any]:
    """The next line of `stream`, parsed as JSON (the emulator prints its port first)."""
    import select

    ready, _, _ = select.select([stream], [], [], timeout_s)
    if not ready:
        raise RuntimeError("the emulator printed nothing")
    payload: dict[str, Any] = json.loads(stream.readline())
    return payload


def log_rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as handle:
        return [row for row in csv.DictReader(handle) if row]


def soak(args: argparse.Namespace) -> dict[str, Any]:
    """Run the soak and return the report (``ok`` and the ``failures`` that made it not ok)."""
    workdir = Path(tempfile.mkdtemp(prefix="snakebot-soak-"))
    log = workdir / "run.csv"
    emulator = subprocess.Popen(
        [
            PYTHON,
            "-m",
            "snakebot",
            "emulate",
            "--robot",
            args.robot,
            "--pty",
            "--physics",
            "--json",
        ],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    burners: list[subprocess.Popen[bytes]] = []
    try:
        port = str(read_json_line(emulator.stdout, 60.0)["port"])
        burners = [subprocess.Popen([PYTHON, "-c", BURN]) for _ in range(args.load)]
        sampler = Sampler(emulator.pid)
        sampler.start()
        began = time.monotonic()
        command = [
            PYTHON,
            "-m",
            "snakebot",
            "run",
            "--backend",
            "dynamixel",
            "--port",
            port,
            "--robot",
            args.robot,
            "--gait",
            args.gait,
            "--rate",
            str(args.rate),
            "--duration",
            str(args.duration),
            "--log",
            str(log),
            "--json",
        ]
        with subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        ) as process:
            sampler.pids.append(process.pid)
            stdout, stderr = process.communicate(timeout=args.duration * 4 + 120)
        run = subprocess.CompletedProcess(command, process.returncode, stdout, stderr)
        wall_s = time.monotonic() - began
        sampler.done.set()
    finally:
        for burner in burners:
            burner.kill()
            burner.wait()
        if emulator.poll() is None:
            emulator.send_signal(signal.SIGINT)
        out, err = emulator.communicate(timeout=60)
    emulated = [json.loads(line) for line in out.splitlines() if line.strip()]
    report = judge(args, run, wall_s, log, emulator.returncode, err, emulated, sampler.samples)
    report["longest_cpu_wait_s"] = round(sampler.starved_s, 3)
    return report


def judge(
    args: argparse.Namespace,
    run: subprocess.CompletedProcess[str],
    wall_s: float,
    log: Path,
    emulator_code: int,
    emulator_err: str,
    emulated: list[dict[str, Any]],
    samples: list[tuple[float, float]],
) -> dict[str, Any]:
    failures: list[str] = []
    summary: dict[str, Any] = {}
    if run.returncode != 0:
        failures.append(f"run exited {run.returncode}: {run.stderr[-2000:]}")
    else:
        summary = json.loads(run.stdout)
    rows = log_rows(log) if log.exists() else []
    cycles = [int(row["cycle"]) for row in rows]
    if not rows or cycles != list(range(len(rows))):
        failures.append(f"telemetry: {len(rows)} rows, cycles not 0..N-1 in order")
    achieved = float(summary.get("achieved_rate_hz") or 0.0)
    if summary and achieved < args.min_rate_fraction * args.rate:
        failures.append(f"achieved {achieved:.1f} Hz of the {args.rate} Hz requested")
    if summary.get("interrupted"):
        failures.append("the run was interrupted")
    twin = emulated[-1] if emulated else {}
    bus = twin.get("bus", {})
    if emulator_code != 0 or not bus:
        failures.append(f"emulator exited {emulator_code}: {emulator_err[-2000:]}")
    for key in ("dropped_bytes", "crc_errors", "stale_resets", "watchdog_trips"):
        if bus.get(key, 0) != 0:
            failures.append(f"emulator {key}: {bus[key]}")
    settled = [mib for t, mib in samples if t >= 0.2 * args.duration]
    growth = settled[-1] - settled[0] if len(settled) >= 2 else 0.0
    if growth > args.max_growth_mib:
        failures.append(f"emulator memory grew {growth:.1f} MiB after the first fifth")
    return {
        "ok": not failures,
        "failures": failures,
        "duration_s": args.duration,
        "rate_hz": args.rate,
        "load_processes": args.load,
        "wall_s": round(wall_s, 1),
        "achieved_rate_hz": round(achieved, 2),
        "overruns": summary.get("overruns"),
        "control_cycles": summary.get("control_cycles"),
        "log_rows": len(rows),
        "emulator_bus": bus,
        "emulator_rss_mib": {
            "first": round(settled[0], 1) if settled else None,
            "last": round(settled[-1], 1) if settled else None,
            "max": round(max(settled), 1) if settled else None,
            "growth": round(growth, 2),
        },
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=60.0, help="seconds of real time")
    parser.add_argument("--rate", type=float, default=50.0, help="requested control rate (Hz)")
    parser.add_argument("--robot", default="snake12")
    parser.add_argument("--gait", default="serpenoid")
    parser.add_argument("--load", type=int, default=2, help="CPU-bound processes beside it")
    parser.add_argument("--min-rate-fraction", type=float, default=0.9)
    parser.add_argument("--max-growth-mib", type=float, default=8.0)
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    args = parser.parse_args(argv)
    report = soak(args)
    if args.json:
        print(json.dumps(report))
    else:
        for key, value in report.items():
            print(f"{key:>18}: {value}")
    return 0 if report["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
