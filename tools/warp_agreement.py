"""How closely the MuJoCo Warp engine agrees with the CPU engine on the same candidates.

Draws ``--count`` points uniformly (seeded) from a gait's default search box, scores each on the
CPU engine (``mujoco.batch``, float64) and on the Warp engine (``--device``), and prints, per
metric, the largest and the median absolute difference (and the median relative one), how often
the two agree on feasibility and on why a run stopped, the Spearman rank correlation of the
losses and the overlap of the two top-k sets. docs/tuning.md quotes its output.

    python tools/warp_agreement.py --robot snake12 --gait sidewinding --count 32 --duration 4
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from snakebot.config import load_robot
from snakebot.tuning.engine_warp import WarpGaitProblem
from snakebot.tuning.objectives import objective_for
from snakebot.tuning.problem import EvalPlan, Evaluation, GaitProblem
from snakebot.tuning.space import build_space, parse_bounds, tuning_base

METRICS = (
    "distance_m",
    "speed_mps",
    "heading_deg",
    "cost_of_transport",
    "positive_work_j",
    "turn_deg",
    "tracking_rms_rad",
)


def _number(value: object) -> float:
    return float(value) if isinstance(value, int | float) else math.nan


def difference(metric: str, cpu: Evaluation, warp: Evaluation) -> tuple[float, float]:
    """(absolute, relative) difference of ``metric`` between the two engines' runs."""
    a, b = _number(cpu.summary.get(metric)), _number(warp.summary.get(metric))
    delta = abs(a - b)
    if metric == "heading_deg":
        delta = abs(math.remainder(a - b, 360.0))
    return delta, delta / abs(a) if a else math.nan


def compare(cpu: list[Evaluation], warp: list[Evaluation], top: int) -> dict[str, object]:
    """The agreement figures of two engines' evaluations of the same points, in order."""
    rows: dict[str, object] = {}
    for metric in METRICS:
        pairs = [difference(metric, a, b) for a, b in zip(cpu, warp, strict=True)]
        absolute = [d for d, _ in pairs if math.isfinite(d)]
        relative = [r for _, r in pairs if math.isfinite(r)]
        rows[metric] = {
            "max_abs": max(absolute),
            "median_abs": statistics.median(absolute),
            "median_rel": statistics.median(relative) if relative else None,
            "runs": len(absolute),
        }
    losses = np.array([[a.loss, b.loss] for a, b in zip(cpu, warp, strict=True)])
    both = [a.feasible and b.feasible for a, b in zip(cpu, warp, strict=True)]
    feasible = losses[np.array(both, dtype=bool)]
    best_cpu = set(np.argsort(losses[:, 0])[:top].tolist())
    best_warp = set(np.argsort(losses[:, 1])[:top].tolist())
    runs = [
        {
            "x": list(a.x),
            "distance_m": [a.summary.get("distance_m"), b.summary.get("distance_m")],
            "loss": [a.loss, b.loss],
            "feasible": [a.feasible, b.feasible],
            "stopped": [a.violations.stopped, b.violations.stopped],
        }
        for a, b in zip(cpu, warp, strict=True)
    ]
    return {
        "runs": runs,
        "metrics": rows,
        "feasible_agree": sum(a.feasible == b.feasible for a, b in zip(cpu, warp, strict=True)),
        "feasible_cpu": sum(a.feasible for a in cpu),
        "stop_agree": sum(
            a.violations.stopped == b.violations.stopped for a, b in zip(cpu, warp, strict=True)
        ),
        "spearman_loss": float(spearmanr(losses[:, 0], losses[:, 1]).statistic),
        "feasible_both": len(feasible),
        "spearman_feasible": float(spearmanr(feasible[:, 0], feasible[:, 1]).statistic)
        if len(feasible) > 2
        else None,
        "top_k": top,
        "top_k_overlap": len(best_cpu & best_warp),
        "best_same": int(np.argmin(losses[:, 0])) == int(np.argmin(losses[:, 1])),
    }


def main() -> None:
    """Run both engines on the same sample and print the table (and --json)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="snake12")
    parser.add_argument("--gait", default="sidewinding")
    parser.add_argument("--count", type=int, default=32)
    parser.add_argument("--duration", type=float, default=4.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--top", type=int, default=8)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--bounds", action="append", default=[], metavar="NAME=LOW:HIGH")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    robot = load_robot(args.robot)
    base = tuning_base(args.gait, robot.joint_count, {})
    limit = float(min(-robot.lower_rad.max(), robot.upper_rad.min()))
    space = build_space(args.gait, base, None, parse_bounds(args.bounds), limit)
    objective = objective_for("speed", 0.0, robot.body_length_m)
    rng = np.random.default_rng(args.seed)
    low = np.array([d.lower for d in space.dims])
    high = np.array([d.upper for d in space.dims])
    points = [low + (high - low) * rng.random(len(low)) for _ in range(args.count)]
    plan = EvalPlan(duration_s=args.duration)
    start = time.perf_counter()
    cpu = GaitProblem(robot, space, objective, plan).evaluate(points)
    cpu_s = time.perf_counter() - start
    warp_plan = EvalPlan(duration_s=args.duration, engine="warp", device=args.device)
    start = time.perf_counter()
    warp = WarpGaitProblem(robot, space, objective, warp_plan).evaluate(points)
    warp_s = time.perf_counter() - start
    result = compare(cpu, warp, args.top)
    result.update(
        robot=args.robot,
        gait=args.gait,
        count=args.count,
        duration_s=args.duration,
        seed=args.seed,
        device=args.device,
        cpu_wall_s=cpu_s,
        warp_wall_s=warp_s,
    )
    sample = f"{args.count} candidates x {args.duration:g} s, seed {args.seed}"
    print(f"{args.robot} {args.gait}: {sample}, device {args.device}")
    print("| metric | max abs diff | median abs diff | median rel diff |")
    print("|---|---|---|---|")
    for metric, row in result["metrics"].items():  # type: ignore[attr-defined]
        rel = row["median_rel"]
        print(
            f"| {metric} | {row['max_abs']:.4g} | {row['median_abs']:.4g} | "
            f"{'n/a' if rel is None else f'{100 * rel:.2g} %'} |"
        )
    print(
        f"feasible agree {result['feasible_agree']}/{args.count} "
        f"(cpu feasible {result['feasible_cpu']}), stop reasons agree "
        f"{result['stop_agree']}/{args.count}, Spearman(loss) {result['spearman_loss']:.3f} "
        f"(feasible on both: {result['feasible_both']}, {result['spearman_feasible']}), "
        f"top-{args.top} overlap {result['top_k_overlap']}/{args.top}, "
        f"same best {result['best_same']}; wall cpu {cpu_s:.1f} s, warp {warp_s:.1f} s"
    )
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
