"""`tune gait` on mass-spring bodies: each candidate is a normal `snakebot run`, in a process pool.

The batched engine (``mujoco.batch``) cannot run Miller's directional rule, which is Python
between physics steps, so a body's candidates go through ``run_gait`` on a ``SoftBodyBackend``,
one process per worker. Scores use the same objectives and the same kind of violations as the
rigid twin's search: commands beyond the channel limits or faster than the muscles' slew limit,
time with no point on the ground, and runs that diverge.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np

from snakebot.backends.softbody import SoftBodyBackend
from snakebot.config.body import BodyConfig
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.errors import PhysicsHealthError, SimulationDivergedError
from snakebot.gaits import make_gait
from snakebot.gaits.spec import ParamValue
from snakebot.tuning.feasibility import Violations
from snakebot.tuning.objectives import Objective
from snakebot.tuning.problem import EvalPlan, Evaluation, EvaluationHistory, Listener
from snakebot.tuning.space import SearchSpace
from snakebot.tuning.trace import FloatArray


@dataclass(frozen=True)
class SoftJob:
    """One candidate for a worker: the body, a gait by name and parameters, and the plan."""

    body: BodyConfig
    gait: str
    params: Mapping[str, object]
    duration_s: float
    rate_hz: float
    friction: float | None = None


@dataclass(frozen=True)
class SoftOutcome:
    """A finished candidate: its `snakebot run --json` summary and how it left the envelope."""

    summary: dict[str, object]
    violations: Violations


def run_soft_job(job: SoftJob) -> SoftOutcome:
    """Run one candidate like `snakebot run --robot BODY --json` and assess it."""
    body = job.body
    gait = make_gait(
        job.gait, body.joint_count, job.params, lower_rad=body.lower_rad, upper_rad=body.upper_rad
    )
    metrics = RunMetrics(body.joint_count, body.body_length_m, body.total_mass_kg)
    plan = RunPlan(job.duration_s, job.rate_hz, ramp_out=False)
    backend = SoftBodyBackend(body, friction=job.friction)
    targets_seen: list[FloatArray] = []
    touching: list[bool] = []

    def sample(record: CycleRecord) -> None:
        targets_seen.append(record.target_rad)
        touching.append(backend.data.ncon > 0)

    stopped = ""
    with backend:
        schedule = plan.schedule(body.safety.ramp_s, float(backend.model.opt.timestep))
        try:
            result = run_gait(
                backend, gait, SafetyLayer.for_robot(body), plan, metrics, observers=[sample]
            )
            summary = result.summary
        except SimulationDivergedError:
            stopped = "diverged"
            summary = metrics.summary(gait.period_s)
        except PhysicsHealthError as exc:  # the body's physics stopped being credible
            stopped = f"physics health: {exc.check}"
            summary = metrics.summary(gait.period_s)
    summary.update(backend.stats.extra)
    targets = np.array(targets_seen) if targets_seen else np.zeros((1, body.joint_count))
    beyond = np.maximum(targets - body.upper_rad, body.lower_rad - targets)
    rate = float(np.abs(np.diff(targets, axis=0)).max(initial=0.0)) * job.rate_hz
    planned = max(schedule.planned_cycles, 1)
    airborne = planned - sum(touching)
    violations = Violations(
        joint_limit_rad=max(float(beyond.max(initial=0.0)), 0.0),
        speed_excess=max(rate / body.max_speed_rad_s - 1.0, 0.0),
        airborne_fraction=airborne / planned,
        stopped=stopped,
    )
    return SoftOutcome(summary, violations)


class SoftGaitProblem(EvaluationHistory):
    """Scores points of ``space`` for ``objective`` by running them on the soft body ``body``.

    The search methods use it as they use ``GaitProblem`` (snakebot.tuning.problem.SearchProblem).
    """

    def __init__(
        self,
        body: BodyConfig,
        space: SearchSpace,
        objective: Objective,
        plan: EvalPlan,
        *,
        listener: Listener | None = None,
    ) -> None:
        self.robot = body
        self.space = space
        self.objective = objective
        self.plan = plan
        self.listener = listener
        self.history: list[Evaluation] = []
        self._friction = None if plan.friction is None else plan.friction.lateral
        self._executor = ProcessPoolExecutor(max_workers=max(1, plan.workers))

    def close(self) -> None:
        """Stop the worker processes."""
        self._executor.shutdown(cancel_futures=True)

    def run(self, params: Sequence[Mapping[str, ParamValue]]) -> list[SoftOutcome]:
        """Run full gait parameter sets across the workers; results in order."""
        jobs = [
            SoftJob(
                self.robot,
                self.space.gait,
                p,
                self.plan.duration_s,
                self.plan.rate_hz,
                self._friction,
            )
            for p in params
        ]
        return list(self._executor.map(run_soft_job, jobs))

    def evaluate(self, points: Sequence[FloatArray] | FloatArray) -> list[Evaluation]:
        """Run every point (D,) and score it; returns them in order."""
        rows = [tuple(float(v) for v in point) for point in points]
        params = [self.space.params(x) for x in rows]
        out = []
        for x, p, outcome in zip(rows, params, self.run(params), strict=True):
            out.append(self._score(x, p, outcome, len(self.history)))
            self.history.append(out[-1])
        if self.listener is not None:
            self.listener(self)
        return out

    def baseline(self) -> Evaluation:
        """The base parameters (defaults and --set), scored but not counted as an evaluation."""
        params = dict(self.space.base)
        outcome = self.run([params])[0]
        return self._score(tuple(float(v) for v in self.space.start()), params, outcome, -1)

    def _score(
        self, x: tuple[float, ...], params: dict[str, ParamValue], outcome: SoftOutcome, index: int
    ) -> Evaluation:
        value = math.nan if outcome.violations.stopped else self.objective.value(outcome.summary)
        loss = self.objective.loss(value, outcome.violations)
        return Evaluation(index, x, params, outcome.summary, outcome.violations, value, loss)
