"""Benchmark: the controller's own cost per control cycle on the twin, stage by stage.

``run_gait`` drives a serpenoid on the real ``TwinBackend`` (the path of ``snakebot run``: gait,
safety layer, the twin's divergence and physics-health checks, read_state, body state, run
metrics), so every part of the cycle a user pays for is in it. What is timed:

- ``cycle``: wall time per control cycle minus the physics (``mj_step``), i.e. what snakebot
  adds to a bare loop; the only instrumentation in this pass is one timer around each call of
  the twin's compiled period (period_c: the period's ``mj_step`` calls, the work integral and
  the period's readouts in one C call). The readouts' share of that call is measured on its own
  (the same call with no physics step, ``--readout-calls`` times after each run) and counted
  as snakebot's, not the physics'.
- per stage (a second pass with a timer around each stage, their own cost calibrated and taken
  off): ``gait`` (gait.command), ``safety`` (SafetyLayer.filter), ``send`` (send_command),
  ``health`` (the physics-health sample), ``advance other`` (the rest of ``advance`` around
  the compiled period, and the period's C readouts: the divergence check, the step count, the
  work, torque, body and health-scan readouts), ``read_state``, ``body_state``,
  ``metrics`` (RunMetrics.add), ``log`` (the CSV writer, with ``--log``) and ``loop`` (what is
  left: the loop's own bookkeeping, the schedule).

Times are the thread's CPU time by default (``--clock cpu``: on a shared machine the time this
process waited for a core does not count; ``--clock wall`` for the wall clock). Medians over
``--repeats`` runs, each ``--seconds`` of robot time at 100 Hz:

    python tools/bench_cycle.py [--repeats 7] [--seconds 10] [--joints 8] [--log] [--clock cpu]
    PYTHONPATH=/path/to/other/checkout python tools/bench_cycle.py   # another tree's code
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

from snakebot.backends.twin import TwinBackend
from snakebot.config import RobotConfig, load_robot
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from snakebot.telemetry import CsvTelemetryWriter

RATE_HZ = 100.0
STAGES = (
    "gait",
    "safety",
    "send",
    "health",
    "advance other",
    "read_state",
    "body_state",
    "metrics",
    "log",
    "loop",
)


CLOCKS = {"cpu": time.thread_time_ns, "wall": time.perf_counter_ns}
now_ns = CLOCKS["cpu"]


class Clock:
    """Nanoseconds spent per stage, and how many timed calls."""

    def __init__(self) -> None:
        self.ns: dict[str, int] = defaultdict(int)
        self.calls: dict[str, int] = defaultdict(int)

    def wrap(self, stage: str, function: Callable[..., Any]) -> Callable[..., Any]:
        ns, calls, clock = self.ns, self.calls, now_ns

        def timed(*args: Any, **kwargs: Any) -> Any:
            start = clock()
            try:
                return function(*args, **kwargs)
            finally:
                ns[stage] += clock() - start
                calls[stage] += 1

        timed.__wrapped__ = function  # type: ignore[attr-defined]
        return timed


class TimedSink:
    """A telemetry sink whose ``__call__`` (one record) is timed."""

    def __init__(self, sink: CsvTelemetryWriter, timed: Callable[[CycleRecord], None]) -> None:
        self._sink, self._timed = sink, timed

    @property
    def rows(self) -> int:
        return self._sink.rows

    def __call__(self, record: CycleRecord) -> None:
        self._timed(record)

    def close(self) -> None:
        self._sink.close()


def wrapper_overhead_ns() -> float:
    """What one timed call costs beyond the call itself (subtracted per call)."""
    clock = Clock()
    bare = clock.wrap("x", lambda: None)
    nothing = lambda: None  # noqa: E731
    n = 20000
    runs = []
    for _ in range(5):
        start = now_ns()
        for _ in range(n):
            nothing()
        plain = now_ns() - start
        start = now_ns()
        for _ in range(n):
            bare()
        runs.append((now_ns() - start - plain) / n)
    return max(min(runs), 0.0)


def robot_with(joints: int) -> RobotConfig:
    base = load_robot("snake8")
    chain = tuple(dataclasses.replace(base.joints[0], servo_id=i + 1) for i in range(joints))
    return dataclasses.replace(base, joints=chain)


def readout_ns(backend: TwinBackend, calls: int) -> float:
    """What one call of the compiled period costs with no physics step: its readouts alone
    (positions, speeds, torques, work totals, COM, head orientation and rate, health scan)."""
    period = getattr(backend, "_period", None)
    if period is None:  # a tree from before period_c: its C stepped and summed work only
        return 0.0
    model, data, pointer = period._pointers
    function = period._function
    start = now_ns()
    for _ in range(calls):
        function(model, data, pointer, 0, 1)
    return (now_ns() - start) / calls


def one_run(
    robot: RobotConfig, seconds: float, log_dir: Path | None, stages: bool
) -> tuple[int, float, Clock]:
    """One run; returns the cycles, the wall seconds and the clock's stage times (with
    ``readout`` the C readouts' cost per period, ns, in ``clock.ns``)."""
    clock = Clock()
    backend = TwinBackend(robot)
    gait = make_gait("serpenoid", robot.joint_count)
    safety = SafetyLayer.for_robot(robot)
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    with backend:
        # The period in C (period_c): its mj_step calls, the work integral and the readouts;
        # in a tree from before period_c (PYTHONPATH=<other tree>), its C work stepper.
        period = getattr(backend, "_period", None)
        if period is not None:
            period._function = clock.wrap("mj_step", period._function)
        else:
            backend._step_integrating = clock.wrap(  # type: ignore[method-assign]
                "mj_step", backend._step_integrating
            )
        log: CsvTelemetryWriter | TimedSink | None = (
            CsvTelemetryWriter(log_dir / "bench.csv", robot.joint_count)
            if log_dir is not None
            else None
        )
        if stages:
            object.__setattr__(gait, "command", clock.wrap("gait", gait.command))
            safety.filter = clock.wrap("safety", safety.filter)  # type: ignore[method-assign]
            backend.send_command = clock.wrap("send", backend.send_command)  # type: ignore[method-assign]
            backend.advance = clock.wrap("advance", backend.advance)  # type: ignore[method-assign]
            backend.read_state = clock.wrap("read_state", backend.read_state)  # type: ignore[method-assign]
            backend.body_state = clock.wrap("body_state", backend.body_state)  # type: ignore[method-assign]
            metrics.add = clock.wrap("metrics", metrics.add)  # type: ignore[method-assign]
            monitor = backend.physics_monitor
            if monitor is not None:
                monitor.sample = clock.wrap("health", monitor.sample)  # type: ignore[method-assign]
            if log is not None:
                log = TimedSink(log, clock.wrap("log", log.__call__))
        plan = RunPlan(duration_s=seconds, rate_hz=RATE_HZ, ramp_out=False)
        start = now_ns()
        run_gait(backend, gait, safety, plan, metrics, log=log)
        wall_ns = now_ns() - start
        if log is not None:
            log.close()
        if period is not None:
            period._function = period._function.__wrapped__
        clock.ns["readout"] = round(readout_ns(backend, 2000))
    return metrics.cycles, wall_ns / 1e9, clock


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--seconds", type=float, default=10.0, help="robot seconds per run")
    parser.add_argument("--joints", type=int, default=8)
    parser.add_argument("--log", action="store_true", help="write the per-cycle CSV log too")
    parser.add_argument(
        "--clock",
        choices=tuple(CLOCKS),
        default="cpu",
        help="cpu: this thread's CPU time (holds on a loaded machine; the default); wall",
    )
    args = parser.parse_args()
    global now_ns
    now_ns = CLOCKS[args.clock]
    robot = robot_with(args.joints)
    overhead = wrapper_overhead_ns()
    own_us: list[float] = []
    physics_us: list[float] = []
    readout_us: list[float] = []
    stage_us: dict[str, list[float]] = {s: [] for s in STAGES}
    with tempfile.TemporaryDirectory() as tmp:
        log_dir = Path(tmp) if args.log else None
        for _ in range(args.repeats):
            cycles, wall, clock = one_run(robot, args.seconds, log_dir, stages=False)
            readouts = clock.ns.pop("readout") * clock.calls["mj_step"]
            step_ns = clock.ns["mj_step"] - overhead * clock.calls["mj_step"] - readouts
            own_us.append((wall * 1e9 - step_ns) / cycles / 1e3)
            physics_us.append(step_ns / cycles / 1e3)
            readout_us.append(readouts / cycles / 1e3)
            cycles, wall, clock = one_run(robot, args.seconds, log_dir, stages=True)
            readouts = clock.ns.pop("readout") * clock.calls["mj_step"]
            clock.ns["mj_step"] -= readouts  # the readouts count in "advance other"
            net = {k: clock.ns[k] - overhead * clock.calls[k] for k in clock.ns}
            # advance holds mj_step and the health sample, each timed on its own (with its timer).
            inside = clock.calls["mj_step"] + clock.calls.get("health", 0)
            net["advance other"] = (
                net.pop("advance") - net["mj_step"] - net.get("health", 0.0) - overhead * inside
            )
            timed = sum(net.values())
            net["loop"] = wall * 1e9 - timed - overhead * sum(clock.calls.values())
            for stage in STAGES:
                stage_us[stage].append(net.get(stage, 0.0) / cycles / 1e3)
    own = statistics.median(own_us)
    print(
        f"{args.joints} joints, {args.repeats} x {args.seconds:g} s at {RATE_HZ:g} Hz"
        f"{' with the CSV log' if args.log else ''}, {args.clock} clock: snakebot's own cost "
        f"{own:.1f} us/cycle median (min {min(own_us):.1f}, max {max(own_us):.1f}); "
        f"mj_step {statistics.median(physics_us):.0f} us/cycle; the period's C readouts "
        f"{statistics.median(readout_us):.1f} us/cycle (in snakebot's own); "
        f"timer overhead {overhead:.0f} ns/call subtracted"
    )
    print("| stage | us/cycle (median) | min-max |")
    print("|---|---|---|")
    for stage in STAGES:
        values = stage_us[stage]
        if not args.log and stage == "log":
            continue
        print(
            f"| {stage} | {statistics.median(values):.1f} | {min(values):.1f}-{max(values):.1f} |"
        )
    total = sum(statistics.median(stage_us[s]) for s in STAGES)
    print(f"| sum of stages | {total:.1f} | |")


if __name__ == "__main__":
    main()
