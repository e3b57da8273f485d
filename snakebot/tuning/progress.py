"""A progress bar on stderr with the best objective so far; plain lines when not a terminal."""

from __future__ import annotations

import math
import sys
import time
from typing import Any, TextIO

from snakebot.tuning.problem import SearchProblem


class ProgressBar:
    """Redrawn after each batch of evaluations; call ``finish`` at the end. Shows candidates per
    second and, on the Ray executor, how many workers are alive.

    On a terminal it redraws one line; elsewhere (CI logs, pipes) it prints a line at most every
    ``every_s`` seconds so logs stay short.
    """

    def __init__(self, budget: int, stream: TextIO | None = None, every_s: float = 5.0) -> None:
        self.budget = max(budget, 1)
        self.stream = stream if stream is not None else sys.stderr
        self.every_s = every_s
        self.start = time.monotonic()
        self._last_line = -math.inf
        self._tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def __call__(self, problem: SearchProblem) -> None:
        """Show the state of ``problem``."""
        now = time.monotonic()
        done = problem.evaluations
        if not self._tty and now - self._last_line < self.every_s and done < self.budget:
            return
        self._last_line = now
        fraction = min(done / self.budget, 1.0)
        bar = "#" * int(fraction * 24)
        text = f"[{bar:<24}] {done}/{self.budget} evals  best {best_text(problem)}"
        elapsed = now - self.start
        text += f"  {elapsed:5.1f} s  {done / elapsed if elapsed > 0 else 0.0:.1f} cand/s"
        live = getattr(problem, "live_workers", None)
        if isinstance(live, int):
            text += f"  {live} worker{'s' * (live != 1)} live"
        rescored = getattr(problem, "rescored", 0)
        if isinstance(rescored, int) and rescored:
            text += f" ({rescored} re-run after a lost worker)"
        if self._tty:
            self.stream.write(f"\r{text:<100}")
        else:
            self.stream.write(text + "\n")
        self.stream.flush()

    def finish(self) -> None:
        """End the redrawn line."""
        if self._tty:
            self.stream.write("\n")
            self.stream.flush()


def best_text(problem: SearchProblem) -> str:
    """The best objective so far with its unit, or why there is none."""
    best = problem.best
    if best is None:
        return "-"
    if not best.feasible:
        return "none playable yet"
    unit = f" {problem.objective.unit}" if problem.objective.unit else ""
    return f"{problem.objective.name} {best.value:.4g}{unit}"


def gait_summary_text(summary: dict[str, Any]) -> str:
    """A readable `tune gait` result from its JSON summary."""
    best, base = summary["best"], summary["baseline"]
    unit = f" {summary['objective_unit']}" if summary["objective_unit"] else ""

    def value(entry: dict[str, Any]) -> str:
        return "n/a" if entry["value"] is None else f"{entry['value']:.4g}{unit}"

    keys = {k.split("[")[0] for d in summary["searched"] for k in d["name"].split("+")}
    shown = {k: v for k, v in best["params"].items() if k in keys}
    shown = {k: "..." if isinstance(v, list | tuple) else v for k, v in shown.items()}
    lines = [
        f"{summary['robot']} / {summary['gait']}: {summary['method']} for {summary['objective']}",
        f"  best       {value(best)}  (baseline {value(base)})",
        "  params     " + ", ".join(f"{k}={_fmt(v)}" for k, v in shown.items()),
        f"  searched   {summary['evaluations']} evaluations ({summary['feasible_evaluations']} "
        f"playable) in {summary['wall_s']:.1f} s on {_where(summary)}",
    ]
    if "gait_file" in summary:
        lines.append(f"  gait file  {summary['gait_file']}")
    if "plots" in summary:
        lines.append(f"  report     {', '.join(summary['plots'])}")
    return "\n".join(lines)


def gain_line(done: int, total: int, score: Any) -> str:
    """One progress line of `tune gains`: the candidate and how it did."""
    gains, pd = score.gains, score.pd
    status = "ok" if score.feasible else score.reason
    return (
        f"  [{done}/{total}] P={gains.position_p} I={gains.position_i} D={gains.position_d} "
        f"(kp {pd.kp_nm_per_rad:.3g} N·m/rad, kd {pd.kd_nms_per_rad:.3g} N·m·s/rad): "
        f"gait tracking {score.tracking_rms_rad:.4f} rad ({status})"
    )


def gains_summary_text(summary: dict[str, Any]) -> str:
    """A readable `tune gains` result from its JSON summary."""
    now, best = summary["current"], summary["best"]
    lines = [
        f"{summary['robot']}: gait tracking {now['tracking_rms_rad']:.4f} rad at P/I/D "
        f"{now['position_p']}/{now['position_i']}/{now['position_d']} -> "
        f"{best['tracking_rms_rad']:.4f} rad at "
        f"{best['position_p']}/{best['position_i']}/{best['position_d']}",
        f"  in SI: kp {now['kp_nm_per_rad']:.4g} -> {best['kp_nm_per_rad']:.4g} N·m/rad, "
        f"kd {now['kd_nms_per_rad']:.4g} -> {best['kd_nms_per_rad']:.4g} N·m·s/rad",
        f"  written to {summary['written_to']}"
        if "written_to" in summary
        else "  robot file unchanged"
        + (f": {summary['not_written']}" if "not_written" in summary else ""),
    ]
    return "\n".join(lines)


def _where(summary: dict[str, Any]) -> str:
    if summary.get("executor") == "ray":
        return f"the Ray cluster at {summary['address']}" if summary.get("address") else "Ray"
    return f"{summary['workers']} workers"


def _fmt(value: object) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)
