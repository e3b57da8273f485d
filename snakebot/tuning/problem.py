"""A gait tuning problem: points of a search space in, scored runs on the twin out.

Every evaluation is kept in order; ``best`` is the lowest loss, so a feasible gait always wins
over one that breaks the servo envelope (objectives.Objective.loss).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Protocol

from snakebot.backends.twin import GroundFriction
from snakebot.backends.twin.friction.scale import FrictionModel
from snakebot.backends.twin.terrain import Terrain
from snakebot.config.body import BodyConfig
from snakebot.config.schema import RobotConfig
from snakebot.gaits import Gait, make_gait
from snakebot.gaits.spec import ParamValue
from snakebot.tuning.commands import GaitCommands
from snakebot.tuning.engine import TwinBatch
from snakebot.tuning.feasibility import Envelope, Violations, assess
from snakebot.tuning.objectives import Objective
from snakebot.tuning.pool import PoolJob, ProcessPool
from snakebot.tuning.space import SearchSpace
from snakebot.tuning.trace import FloatArray, Trace, summarise

if TYPE_CHECKING:
    from snakebot.tuning.executor_ray import RayEvaluator

ENGINES = ("batch", "processes", "warp")
EXECUTORS = ("local", "ray")
"""Where candidates run: ``local`` on this machine's engine; ``ray`` on Ray actors, one per node
(snakebot.tuning.executor_ray), at ``EvalPlan.address`` or on a Ray started here."""


@dataclass(frozen=True)
class Evaluation:
    """One scored candidate: its point, full gait params, run summary, violations and loss."""

    index: int
    x: tuple[float, ...]
    params: dict[str, ParamValue]
    summary: dict[str, object]
    violations: Violations
    value: float
    loss: float

    @property
    def feasible(self) -> bool:
        """True when the run stayed inside the servo envelope."""
        return self.violations.feasible


@dataclass(frozen=True)
class EvalPlan:
    """How each candidate runs: like ``snakebot run --duration D --rate R`` on the twin.

    ``executor`` says where (EXECUTORS); ``address`` is the Ray cluster's ``HOST:PORT`` for the
    ``ray`` executor (None: start Ray on this machine).
    """

    duration_s: float = 10.0
    rate_hz: float = 100.0
    workers: int = 2
    engine: str = "batch"
    device: str = "cpu"  # the Warp device of engine "warp" ("cpu", "cuda", "cuda:1", ...)
    allow_roll: bool = False
    friction: GroundFriction | None = None
    terrain: Terrain | None = None
    friction_model: FrictionModel | None = None
    executor: str = "local"
    address: str | None = None


class SearchProblem(Protocol):
    """What the search methods and the progress bar use of a problem: GaitProblem on the rigid
    twin, snakebot.tuning.softbody.SoftGaitProblem on a mass-spring body."""

    @property
    def robot(self) -> RobotConfig | BodyConfig:
        """The robot or body the candidates run on."""

    @property
    def space(self) -> SearchSpace:
        """The search space."""

    @property
    def objective(self) -> Objective:
        """What is optimised."""

    @property
    def plan(self) -> EvalPlan:
        """How each candidate runs."""

    @property
    def history(self) -> list[Evaluation]:
        """Every evaluation so far, in order."""

    @property
    def evaluations(self) -> int:
        """Candidates run so far."""

    @property
    def best(self) -> Evaluation | None:
        """The lowest-loss evaluation so far."""

    def evaluate(self, points: Sequence[FloatArray] | FloatArray) -> list[Evaluation]:
        """Run and score every point (D,), in order."""

    def baseline(self) -> Evaluation:
        """The base parameters, scored but not counted."""

    def close(self) -> None:
        """Release workers."""


Listener = Callable[[SearchProblem], None]


class EvaluationHistory:
    """``history``, every evaluation in order, and what the search reads of it."""

    history: list[Evaluation]

    @property
    def evaluations(self) -> int:
        """Candidates run so far."""
        return len(self.history)

    @property
    def best(self) -> Evaluation | None:
        """The lowest-loss evaluation so far (the first one found, on ties)."""
        return min(self.history, key=lambda e: e.loss, default=None)


class GaitProblem(EvaluationHistory):
    """Scores points of ``space`` for ``objective`` by running them on the twin of ``robot``."""

    def __init__(
        self,
        robot: RobotConfig,
        space: SearchSpace,
        objective: Objective,
        plan: EvalPlan,
        *,
        listener: Listener | None = None,
    ) -> None:
        self._check_plan(plan)
        self.robot = robot
        self.space = space
        self.objective = objective
        self.plan = plan
        self.listener = listener
        self.history: list[Evaluation] = []
        self._twin = TwinBatch(
            robot,
            workers=plan.workers,
            friction=plan.friction,
            terrain=plan.terrain,
            friction_model=plan.friction_model,
        )
        self.envelope = Envelope.for_robot(
            robot, float(self._twin.start_com_m[2]), allow_roll=plan.allow_roll
        )
        if plan.terrain is not None and plan.terrain.name != "flat":
            # The airborne check measures heights above the floor plane at z = 0; off the flat
            # floor (a plateau, a slope, a step) that is not the ground, so it is not judged.
            self.envelope = replace(
                self.envelope, contact_tolerance_m=math.inf, lift_limit_m=math.inf
            )
        self._pool = ProcessPool(plan.workers) if plan.engine == "processes" else None
        self._remote: RayEvaluator | None = None
        if plan.executor == "ray":
            from snakebot.tuning.executor_ray import RayEvaluator

            self._remote = RayEvaluator(robot, space, objective, plan)
        self._start_engine()

    @staticmethod
    def _check_plan(plan: EvalPlan) -> None:
        """Raise ConfigError (naming the field) for a plan this problem cannot run; called
        before anything is built. The CPU engines run every plan."""

    def _start_engine(self) -> None:
        """Build what scores the candidates besides the twin, the pool and the Ray actors;
        called last in ``__init__``. The CPU engines need nothing more."""

    def close(self) -> None:
        """Release the worker processes or Ray actors, if any."""
        if self._pool is not None:
            self._pool.close()
        if self._remote is not None:
            self._remote.close()

    @property
    def live_workers(self) -> int | None:
        """Ray actors alive now (the ``ray`` executor), None on the local one."""
        return None if self._remote is None else self._remote.live_workers

    @property
    def rescored(self) -> int:
        """Candidates scored again because the Ray worker holding them was lost (0 locally)."""
        return 0 if self._remote is None else self._remote.rescored

    def evaluate(self, points: Sequence[FloatArray] | FloatArray) -> list[Evaluation]:
        """Run every point (D,) on the twin in parallel and score it; returns them in order."""
        rows = [tuple(float(v) for v in point) for point in points]
        out = []
        if self._remote is not None:
            for scored in self._remote.evaluate(rows):
                out.append(replace(scored, index=len(self.history)))
                self.history.append(out[-1])
        else:
            params = [self.space.params(x) for x in rows]
            outcomes = self.outcomes(params)
            for x, p, (summary, violations) in zip(rows, params, outcomes, strict=True):
                out.append(self.score(x, p, summary, violations, len(self.history)))
                self.history.append(out[-1])
        if self.listener is not None:
            self.listener(self)
        return out

    def baseline(self) -> Evaluation:
        """The base parameters (defaults and --set), scored but not counted as an evaluation."""
        if self._remote is not None:
            return self._remote.baseline()
        params = dict(self.space.base)
        summary, violations = self.outcomes([params])[0]
        start = tuple(float(v) for v in self.space.start())
        return self.score(start, params, summary, violations, -1)

    def outcomes(
        self, params: Sequence[Mapping[str, ParamValue]]
    ) -> list[tuple[dict[str, object], Violations]]:
        """Each parameter set's run summary and violations (the Warp engine's subclass,
        snakebot.tuning.engine_warp.WarpGaitProblem, measures them on its device instead)."""
        out = []
        for p, trace in zip(params, self.run(params), strict=True):
            summary = summarise(trace, self.robot, self.gait(p).period_s)
            out.append((summary, assess(trace, self.envelope, self.plan.duration_s)))
        return out

    def run(self, params: Sequence[Mapping[str, ParamValue]]) -> list[Trace]:
        """The raw runs of full gait parameter sets, on the chosen engine."""
        plan, robot = self.plan, self.robot
        if self._pool is not None:
            jobs = [
                PoolJob(
                    robot,
                    self.space.gait,
                    p,
                    plan.duration_s,
                    plan.rate_hz,
                    self.envelope,
                    plan.friction,
                    plan.terrain,
                    plan.friction_model,
                )
                for p in params
            ]
            return self._pool.run(jobs)
        gaits = [self.gait(p) for p in params]
        commands = GaitCommands(gaits, robot)
        return self._twin.run(commands, plan.duration_s, plan.rate_hz, envelope=self.envelope)

    def gait(self, params: Mapping[str, ParamValue]) -> Gait:
        """The gait ``params`` describe, with the robot's joint limits."""
        robot = self.robot
        return make_gait(
            self.space.gait,
            robot.joint_count,
            params,
            lower_rad=robot.lower_rad,
            upper_rad=robot.upper_rad,
        )

    def score(
        self,
        x: tuple[float, ...],
        params: dict[str, ParamValue],
        summary: dict[str, object],
        violations: Violations,
        index: int,
    ) -> Evaluation:
        """The objective value and loss of one run's summary and violations."""
        value = self.objective.value(summary) if not violations.stopped else math.nan
        loss = self.objective.loss(value, violations)
        return Evaluation(index, x, params, summary, violations, value, loss)
