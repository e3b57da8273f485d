"""`tune gait` without the command line: run a method, keep the result, write it out."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

from snakebot.config.body import BodyConfig
from snakebot.config.loader import resolve_robot_path
from snakebot.config.schema import RobotConfig
from snakebot.errors import ConfigError
from snakebot.gaits import check_joint_axes, save_gait_file
from snakebot.tuning.genetic import Generation, genetic_search
from snakebot.tuning.grid import GridResult, grid_search
from snakebot.tuning.objectives import Objective
from snakebot.tuning.problem import EvalPlan, Evaluation, GaitProblem, Listener, SearchProblem
from snakebot.tuning.space import SearchSpace

METHODS = ("grid", "cmaes", "ga")
DEFAULT_BUDGET = {"grid": 100, "cmaes": 100, "ga": 160}


@dataclass(frozen=True)
class TuneResult:
    """Everything a tuning run produced: every evaluation in order, the best, the baseline."""

    robot: RobotConfig | BodyConfig
    method: str
    objective: Objective
    space: SearchSpace
    plan: EvalPlan
    seed: int
    budget: int
    history: tuple[Evaluation, ...]
    best: Evaluation
    baseline: Evaluation
    wall_s: float
    grid: GridResult | None = None
    generations: tuple[Generation, ...] = ()
    cmaes_best: tuple[float, ...] = field(default=())

    def summary(self) -> dict[str, object]:
        """The JSON report: what was searched, the best and baseline gaits, cost."""
        return {
            "robot": self.robot.name,
            "gait": self.space.gait,
            "method": self.method,
            "objective": self.objective.name,
            "objective_unit": self.objective.unit,
            "heading_deg": self.objective.heading_deg,
            "searched": [
                {"name": d.name, "lower": d.lower, "upper": d.upper} for d in self.space.dims
            ],
            "best": evaluation_dict(self.best),
            "baseline": evaluation_dict(self.baseline),
            "improvement": self.improvement,
            "evaluations": len(self.history),
            "feasible_evaluations": sum(e.feasible for e in self.history),
            "budget": self.budget,
            "wall_s": self.wall_s,
            "engine": self.plan.engine,
            **({"device": self.plan.device} if self.plan.engine == "warp" else {}),
            "executor": self.plan.executor,
            **({"address": self.plan.address} if self.plan.executor == "ray" else {}),
            "workers": self.plan.workers,
            "seed": self.seed,
            "duration_s": self.plan.duration_s,
            "rate_hz": self.plan.rate_hz,
            "terrain": self.plan.terrain.spec_text() if self.plan.terrain else "flat",
        }

    @property
    def improvement(self) -> float | None:
        """Best minus baseline objective value (positive = better for speeds), if both exist."""
        if not (self.best.feasible and self.baseline.feasible):
            return None
        delta = self.best.value - self.baseline.value
        return delta if self.objective.maximise else -delta


def evaluation_dict(evaluation: Evaluation) -> dict[str, object]:
    """One evaluation, JSON-ready (params, objective value, run metrics, violations)."""
    value = evaluation.value
    return {
        "index": evaluation.index,
        "params": dict(evaluation.params),
        "value": None if math.isnan(value) else value,
        "feasible": evaluation.feasible,
        "loss": evaluation.loss,
        "metrics": evaluation.summary,
        "violations": evaluation.violations.as_dict(),
    }


def tune_gait(
    robot: RobotConfig | BodyConfig,
    space: SearchSpace,
    objective: Objective,
    method: str,
    *,
    budget: int,
    seed: int = 0,
    plan: EvalPlan | None = None,
    listener: Listener | None = None,
) -> TuneResult:
    """Search ``space`` with ``method`` for at most ``budget`` evaluations on the twin (or, for a
    mass-spring body, through the normal runner in a process pool)."""
    plan = plan or EvalPlan()
    start = time.perf_counter()
    problem: SearchProblem
    if isinstance(robot, BodyConfig):
        from snakebot.tuning.softbody import SoftGaitProblem

        if plan.engine == "warp":
            raise ConfigError("engine", "warp", "a mass-spring body tunes through the runner")
        if plan.executor != "local":
            raise ConfigError("executor", plan.executor, "a mass-spring body tunes locally only")
        plan = replace(plan, engine="processes")
        problem = SoftGaitProblem(robot, space, objective, plan, listener=listener)
    else:
        check_joint_axes(space.gait, [joint.axis for joint in robot.joints], robot.name)
        if plan.engine == "warp":
            from snakebot.tuning.engine_warp import WarpGaitProblem

            problem = WarpGaitProblem(robot, space, objective, plan, listener=listener)
        else:
            problem = GaitProblem(robot, space, objective, plan, listener=listener)
    try:
        grid: GridResult | None = None
        generations: tuple[Generation, ...] = ()
        cma: tuple[float, ...] = ()
        if method == "grid":
            # The Warp engine runs the whole grid as one batch of worlds.
            grid = grid_search(problem, budget, chunk=budget if plan.engine == "warp" else 20)
        elif method == "cmaes":
            from snakebot.tuning.cmaes import cmaes_search

            cma = tuple(cmaes_search(problem, budget, seed))
        else:
            generations = tuple(genetic_search(problem, budget, seed))
        baseline = problem.baseline()
    finally:
        problem.close()
    best = problem.best
    assert best is not None
    return TuneResult(
        robot=robot,
        method=method,
        objective=objective,
        space=space,
        plan=plan,
        seed=seed,
        budget=budget,
        history=tuple(problem.history),
        best=best,
        baseline=baseline,
        wall_s=time.perf_counter() - start,
        grid=grid,
        generations=generations,
        cmaes_best=cma,
    )


def replay_command(result: TuneResult, path: Path) -> str:
    """The `snakebot run` command line that replays the best gait as it was scored."""
    plan, robot = result.plan, result.robot
    try:
        named = resolve_robot_path(robot.name).resolve() == robot.source.resolve()
    except ConfigError:
        named = False
    command = (
        f"snakebot run --robot {robot.name if named else robot.source} --gait-file {path} "
        f"--duration {plan.duration_s:g} --rate {plan.rate_hz:g}"
    )
    if plan.friction is not None:
        command += f" --friction {plan.friction.axial:g},{plan.friction.lateral:g}"
        if plan.friction.backward is not None:
            command = command.replace(
                f"{plan.friction.axial:g},",
                f"{plan.friction.axial:g},{plan.friction.backward:g},",
            )
    if plan.terrain is not None:
        command += f" --terrain {plan.terrain.spec_text()}"
    if plan.friction_model is not None:
        command += f" --friction-model {plan.friction_model}"
    return command


def save_best_gait(result: TuneResult, path: Path) -> None:
    """Write the best gait as a gait file ``snakebot run --gait-file`` replays to the same run."""
    best = result.best
    metrics = {
        k: v
        for k, v in best.summary.items()
        if k in ("distance_m", "speed_mps", "heading_deg", "cost_of_transport", "tracking_rms_rad")
        and isinstance(v, float)
    }
    plan = result.plan
    meta: dict[str, object] = {
        "tuned_by": f"snakebot tune gait --method {result.method}",
        "robot": result.robot.name,
        "objective": result.objective.name,
        "feasible": best.feasible,
        "evaluations": len(result.history),
        "seed": result.seed,
        "duration_s": plan.duration_s,
        "rate_hz": plan.rate_hz,
        "replay": replay_command(result, path),
        "metrics": metrics,
    }
    if not math.isnan(best.value):
        meta["value"] = best.value
    save_gait_file(path, result.space.gait, best.params, meta)
