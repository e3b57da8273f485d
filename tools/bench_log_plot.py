"""How long `snakebot log plot` takes on a 20 s log (issue 13: under 5 s).

Makes a 20 s twin log of snake12 at 100 Hz (2101 rows with the ramp-out), then times the whole
command (a fresh process: imports included) and the plotting alone (in process, the log read
and matplotlib imported), median of --repeats runs each: wall time, and the CPU time the work
took, which a shared machine's load does not inflate.

    .venv/bin/python tools/bench_log_plot.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        log = Path(folder) / "run20.csv"
        subprocess.run(
            [
                sys.executable,
                "-m",
                "snakebot",
                "run",
                "--robot",
                "snake12",
                "--gait",
                "sidewinding",
                "--duration",
                "20",
                "--log",
                str(log),
                "--json",
            ],
            check=True,
            capture_output=True,
        )
        command, command_cpu = [], []
        for repeat in range(args.repeats):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            start = time.perf_counter()
            subprocess.run(
                [
                    sys.executable,
                    "-m",
                    "snakebot",
                    "log",
                    "plot",
                    str(log),
                    "--out",
                    f"{folder}/cli{repeat}",
                ],
                check=True,
                capture_output=True,
            )
            command.append(time.perf_counter() - start)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            command_cpu.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)

        from snakebot.telemetry import read_log
        from snakebot.telemetry.plots import plot_log, pyplot
        from snakebot.telemetry.sidecar import read_sidecar

        pyplot()
        table = read_log(log)
        sidecar = read_sidecar(log)
        plotting, plotting_cpu = [], []
        for repeat in range(args.repeats):
            out = Path(folder) / f"inproc{repeat}"
            out.mkdir()
            start, start_cpu = time.perf_counter(), time.process_time()
            plot_log(table, sidecar, out)
            plotting.append(time.perf_counter() - start)
            plotting_cpu.append(time.process_time() - start_cpu)
    rows = len(table.values)
    print(f"log: {rows} rows x {table.joints('command_rad').shape[1]} joints")
    print(f"load average {' '.join(f'{x:.1f}' for x in os.getloadavg())} on {os.cpu_count()} CPUs")
    for name, wall, cpu in (
        ("snakebot log plot (process)", command, command_cpu),
        ("plot_log (in process)", plotting, plotting_cpu),
    ):
        print(
            f"{name:<28} wall median {statistics.median(wall):.2f} s (min {min(wall):.2f}), "
            f"CPU median {statistics.median(cpu):.2f} s (min {min(cpu):.2f})"
        )


if __name__ == "__main__":
    main()
