"""Run the pty and hardware-in-the-loop tests N times in a row beside CPU-bound processes.

The real-time tests must hold on a busy machine, not only on a quiet one. This starts ``--hogs``
processes that spin on a CPU each, then runs ``pytest -m MARKER`` ``--runs`` times, one after
the other, and reports each run's outcome, wall time and the load average around it. It stops
the hogs on every exit path (including Ctrl-C).

Usage::

    python tools/pty_under_load.py --runs 10 --hogs 2            # -m pty (soak included)
    python tools/pty_under_load.py --runs 10 --marker "pty and not soak" --json

Exit status: 0 when every run passed, 1 when any failed (its log is kept under ``--logs``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

_SPIN = "while True:\n    pass\n"


@dataclass(frozen=True)
class RunOutcome:
    """One pytest run: whether it passed, its last summary line, wall seconds, load averages."""

    index: int
    passed: bool
    summary: str
    wall_s: float
    load_before: float
    load_after: float
    log: str


def _summary_line(text: str) -> str:
    lines = [line for line in text.strip().splitlines() if line.strip()]
    return lines[-1].strip("= ") if lines else ""


def run_series(runs: int, hogs: int, marker: str, logs: Path, extra: list[str]) -> list[RunOutcome]:
    """Run ``pytest -m marker`` ``runs`` times beside ``hogs`` spinning processes.

    Returns one :class:`RunOutcome` per run; the hogs are stopped before returning or raising.
    """
    logs.mkdir(parents=True, exist_ok=True)
    spinners = [subprocess.Popen([sys.executable, "-c", _SPIN]) for _ in range(hogs)]
    outcomes: list[RunOutcome] = []
    try:
        for index in range(1, runs + 1):
            log = logs / f"run{index:02d}.log"
            load_before = os.getloadavg()[0]
            start = time.monotonic()
            with log.open("w", encoding="utf-8") as out:
                code = subprocess.call(
                    [
                        sys.executable,
                        "-m",
                        "pytest",
                        "-q",
                        "-p",
                        "no:cacheprovider",
                        "-m",
                        marker,
                        *extra,
                    ],
                    stdout=out,
                    stderr=subprocess.STDOUT,
                )
            wall = time.monotonic() - start
            text = log.read_text(encoding="utf-8", errors="replace")
            outcome = RunOutcome(
                index,
                code == 0,
                _summary_line(text),
                round(wall, 1),
                load_before,
                os.getloadavg()[0],
                str(log),
            )
            outcomes.append(outcome)
            print(
                f"run {index}: {'ok' if outcome.passed else 'FAILED'} {outcome.summary} "
                f"({outcome.wall_s:.0f} s, load {load_before:.1f} -> {outcome.load_after:.1f})",
                flush=True,
            )
    finally:
        for spinner in spinners:
            spinner.kill()
            spinner.wait()
    return outcomes


def main(argv: list[str] | None = None) -> int:
    """Parse arguments, run the series, print a report; exit 0 only when every run passed."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10, help="pytest runs in a row (default 10)")
    parser.add_argument("--hogs", type=int, default=2, help="CPU-bound processes (default 2)")
    parser.add_argument("--marker", default="pty", help='pytest -m expression (default "pty")')
    parser.add_argument(
        "--logs",
        type=Path,
        default=Path("pty-under-load"),
        help="directory for each run's pytest output",
    )
    parser.add_argument("--json", action="store_true", help="print the outcomes as JSON at the end")
    parser.add_argument("pytest_args", nargs="*", help="more arguments for pytest (after --)")
    args = parser.parse_args(argv)
    if args.runs < 1 or args.hogs < 0:
        parser.error("--runs must be at least 1 and --hogs at least 0")
    outcomes = run_series(args.runs, args.hogs, args.marker, args.logs, args.pytest_args)
    passed = sum(outcome.passed for outcome in outcomes)
    print(f"passed {passed} of {len(outcomes)} with {args.hogs} CPU hogs (-m {args.marker!r})")
    if args.json:
        print(json.dumps([asdict(outcome) for outcome in outcomes], indent=2))
    return 0 if passed == len(outcomes) else 1


if __name__ == "__main__":
    raise SystemExit(main())
