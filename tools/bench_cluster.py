"""Gait search on Ray against the local executor: candidates/s, Ray's overhead, a projection.

    python tools/bench_cluster.py throughput [--candidates 48] [--batch 6]
    python tools/bench_cluster.py same        # issue 26's "Done when": snake12, CMA-ES, budget 64
    python tools/bench_cluster.py all

throughput: snake12 candidates like `snakebot run --duration 10` (serpenoid, omega x phase_lag,
the default search), scored in batches of ``--batch`` (default: CMA-ES's population for that
search on 2 workers, 6) with ``local`` (mujoco.batch, 2 threads), ``ray`` on one loopback node
(2 CPUs: one actor, 2 threads) and ``ray`` on two loopback nodes (1 CPU each: two actors). The
Ray figures come from the executor's own timing (snakebot.tuning.executor_ray.Timing): the
overhead per candidate is a generation's wall time less its longest share's run time on its
actor, over the candidates. The first batch (actors starting, models building) is not timed.
From the two-node figures it projects candidates/s on a 64-core cluster, as a range.

same: `snakebot tune gait --robot snake12 --method cmaes --budget 64` with `--executor local`
and `--executor ray` (Ray started on this machine, no address); prints both best gaits.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass, replace

import numpy as np

from snakebot.cluster import ray_session
from snakebot.config import load_robot
from snakebot.testing.cluster import LoopbackCluster
from snakebot.tuning.executor_ray import RayEvaluator, Timing
from snakebot.tuning.objectives import objective_for
from snakebot.tuning.problem import EvalPlan, GaitProblem
from snakebot.tuning.space import SearchSpace, build_space, tuning_base

DURATION_S = 10.0
ROBOT = "snake12"
PROJECTED_CORES = 64


@dataclass(frozen=True)
class Measured:
    """One executor's figures over the timed batches."""

    name: str
    candidates: int
    wall_s: float
    overhead_s_per_candidate: float | None = None
    compute_s_per_candidate: float | None = None
    threads_per_actor: int = 2

    @property
    def rate(self) -> float:
        """Candidates per second."""
        return self.candidates / self.wall_s


def load() -> float:
    """The 1-minute load average: other processes' share of the two cores, roughly."""
    return os.getloadavg()[0]


def space() -> SearchSpace:
    robot = load_robot(ROBOT)
    return build_space("serpenoid", tuning_base("serpenoid", robot.joint_count, {}), None, {}, 1.5)


def rows(count: int) -> list[np.ndarray]:
    box = space()
    rng = np.random.default_rng(0)
    return [
        box.lower + rng.uniform(size=len(box.dims)) * (box.upper - box.lower) for _ in range(count)
    ]


def measure(name: str, plan: EvalPlan, points: list[np.ndarray], batch: int) -> Measured:
    robot = load_robot(ROBOT)
    objective = objective_for("speed", 0.0, robot.body_length_m)
    scorer: GaitProblem | RayEvaluator
    if plan.executor == "ray":
        scorer = RayEvaluator(robot, space(), objective, plan)
    else:
        scorer = GaitProblem(robot, space(), objective, plan)
    as_rows = [tuple(float(v) for v in p) for p in points]
    try:
        scorer.evaluate(as_rows[:batch])  # warm-up: actors start, models build
        if isinstance(scorer, RayEvaluator):
            scorer.timing = Timing()
        start = time.perf_counter()
        for first in range(batch, len(points), batch):
            scorer.evaluate(as_rows[first : first + batch])
        wall = time.perf_counter() - start
        timed = len(points) - batch
        if not isinstance(scorer, RayEvaluator):
            return Measured(name, timed, wall)
        timing = scorer.timing
        return Measured(
            name,
            timed,
            wall,
            timing.overhead_s_per_candidate,
            timing.compute_s_per_candidate,
            int(max(scorer.actor_cpus)),
        )
    finally:
        scorer.close()


def throughput(count: int, batch: int) -> None:
    points = rows(count + batch)
    plan = EvalPlan(duration_s=DURATION_S, workers=2)
    loads = [load()]
    results = [measure("local (2 threads)", plan, points, batch)]
    loads.append(load())
    for nodes, cpus in ((1, 2), (2, 1)):
        started = time.perf_counter()
        with LoopbackCluster(nodes, cpus_per_node=cpus) as cluster, ray_session(cluster.address):
            startup = time.perf_counter() - started
            ray_plan = replace(plan, executor="ray", address=cluster.address)
            label = f"ray, {nodes} node{'s' * (nodes > 1)} x {cpus} CPU"
            results.append(measure(label, ray_plan, points, batch))
            print(f"  ({label}: cluster up in {startup:.0f} s)")
        loads.append(load())
    print(
        f"\n{ROBOT}: {count} candidates x {DURATION_S:g} s in batches of {batch}, "
        f"{os.cpu_count()} cores, 1-min load {min(loads):.2f}-{max(loads):.2f}"
    )
    print(f"  {'executor':<24} {'cand/s':>7} {'run s/cand':>11} {'overhead ms/cand':>17} {'%':>6}")
    for m in results:
        if m.overhead_s_per_candidate is None or m.compute_s_per_candidate is None:
            print(f"  {m.name:<24} {m.rate:>7.2f}")
            continue
        share = m.overhead_s_per_candidate / m.compute_s_per_candidate
        print(
            f"  {m.name:<24} {m.rate:>7.2f} {m.compute_s_per_candidate:>11.3f} "
            f"{m.overhead_s_per_candidate * 1e3:>17.1f} {share:>6.1%}"
        )
    project(results[-1])


def project(two_nodes: Measured) -> None:
    """Candidates/s on PROJECTED_CORES cores from the one-thread actors' figures: a range from
    the overhead staying serial on the driver to it spreading like the work."""
    assert two_nodes.compute_s_per_candidate is not None
    assert two_nodes.overhead_s_per_candidate is not None
    per_core_s = two_nodes.compute_s_per_candidate * two_nodes.threads_per_actor
    overhead = two_nodes.overhead_s_per_candidate
    ideal = PROJECTED_CORES / per_core_s
    serial = 1.0 / (per_core_s / PROJECTED_CORES + overhead)
    spread = PROJECTED_CORES / (per_core_s + overhead * 2)  # 2: the overhead measured on 2 actors
    print(
        f"\nprojection, {PROJECTED_CORES} cores in generations of >= {PROJECTED_CORES} candidates: "
        f"{serial:.0f}-{spread:.0f} cand/s (no overhead at all: {ideal:.0f}); "
        f"one core: {per_core_s:.3f} s per candidate"
    )


def same() -> None:
    command = [sys.executable, "-m", "snakebot", "tune", "gait", "--robot", ROBOT]
    command += ["--method", "cmaes", "--budget", "64", "--json", "--quiet"]
    out = {}
    for executor in ("local", "ray"):
        start = time.perf_counter()
        done = subprocess.run(
            [*command, "--executor", executor], check=True, capture_output=True, text=True
        )
        summary = json.loads(done.stdout)
        out[executor] = summary
        best = summary["best"]
        print(
            f"  {executor:<6} best {best['value']!r} m/s at "
            f"{json.dumps({k: best['params'][k] for k in ('omega', 'phase_lag')})}, "
            f"{summary['evaluations']} evaluations in {time.perf_counter() - start:.1f} s"
        )
    print("  same best gait and score:", out["local"]["best"] == out["ray"]["best"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("what", choices=("throughput", "same", "all"))
    parser.add_argument("--candidates", type=int, default=48)
    parser.add_argument("--batch", type=int, default=6)
    args = parser.parse_args()
    if args.what in ("throughput", "all"):
        throughput(args.candidates, args.batch)
    if args.what in ("same", "all"):
        same()


if __name__ == "__main__":
    main()
