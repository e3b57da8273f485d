"""Gait search on a Ray cluster: one actor per node scores its share of every generation.

Each actor builds the robot's twin once (a whole :class:`GaitProblem` on the local executor,
``workers`` = the node's CPUs as ``mujoco.batch`` threads) and then scores the rows it is sent
with the batched engine, returning small :class:`Evaluation` records rather than traces. The
search method (CMA-ES, GA, grid) asks and tells on the driver as with the local executor, and
since a run is bit-identical at any batch split and thread count (snakebot.tuning.engine), the
candidates, scores and best gait are the same for a given seed.

A share whose actor dies (its node lost, its process killed) goes back to the queue and is
scored by the actors still alive; nodes that join later get an actor at the next generation.
Only when no node is left does the search fail, with a ClusterError.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

from snakebot.cluster.session import ClusterInfo, connect, disconnect, require_ray
from snakebot.config.schema import RobotConfig
from snakebot.errors import ClusterError
from snakebot.tuning.objectives import Objective
from snakebot.tuning.problem import EvalPlan, Evaluation, GaitProblem
from snakebot.tuning.space import SearchSpace

Row = tuple[float, ...]
READY_TIMEOUT_S = 600.0
"""How long a generation waits for a first actor to be ready (model built) before failing."""
MAX_FAILED_STARTS = 8
"""Actors that may die before they start, one after another, before the search gives up."""


class ShardWorker:
    """What each Ray actor holds: the twin of one robot and the scoring of a GaitProblem.

    The model is built by :meth:`ready`, not in ``__init__``, so a bad robot or plan comes back
    to the driver as its own error (a ConfigError, say) rather than as a dead actor.
    """

    def __init__(
        self,
        robot: RobotConfig,
        space: SearchSpace,
        objective: Objective,
        plan: EvalPlan,
        threads: int,
    ) -> None:
        local = replace(plan, executor="local", address=None, workers=max(1, threads))
        self._args = (robot, space, objective, local)
        self._problem: GaitProblem | None = None

    def ready(self) -> int:
        """Build the model (once); returns the thread count."""
        return self.problem().plan.workers

    def problem(self) -> GaitProblem:
        """The actor's GaitProblem, built on first use."""
        if self._problem is None:
            self._problem = GaitProblem(*self._args)
        return self._problem

    def evaluate(self, rows: Sequence[Row]) -> tuple[list[Evaluation], float]:
        """Run and score ``rows`` (points of the space); indices are left to the driver. Also
        returns the seconds it took here, so the driver can tell Ray's overhead apart."""
        start = time.perf_counter()
        problem = self.problem()
        params = [problem.space.params(x) for x in rows]
        outcomes = problem.outcomes(params)
        scored = [
            problem.score(x, p, summary, violations, -1)
            for x, p, (summary, violations) in zip(rows, params, outcomes, strict=True)
        ]
        return scored, time.perf_counter() - start

    def baseline(self) -> Evaluation:
        """The base parameters, scored."""
        return self.problem().baseline()


@dataclass
class _Actor:
    node_id: str
    cpus: float
    handle: Any
    ready: Any  # the ObjectRef of handle.ready(), until it resolves
    live: bool = False


@dataclass
class Timing:
    """Where the Ray executor's time went, summed over generations (seconds).

    ``wall_s``: from handing a generation out to having all its scores; ``critical_s``: the
    longest share's own run time on its actor, per generation (the least ``wall_s`` could be);
    ``compute_s``: every share's run time on its actor. ``wall_s - critical_s`` is Ray's
    overhead (scheduling, transfer, the driver's own work) plus re-runs after a lost worker; the
    first generation's also holds the actors' start (Ray workers starting, models building).
    """

    candidates: int = 0
    generations: int = 0
    wall_s: float = 0.0
    critical_s: float = 0.0
    compute_s: float = 0.0

    @property
    def overhead_s_per_candidate(self) -> float:
        """Seconds of overhead per candidate scored."""
        return (self.wall_s - self.critical_s) / max(self.candidates, 1)

    @property
    def compute_s_per_candidate(self) -> float:
        """Seconds a candidate takes on its actor (within a batch on the actor's threads)."""
        return self.compute_s / max(self.candidates, 1)


@dataclass(frozen=True)
class _Share:
    start: int
    rows: tuple[Row, ...]


class RayEvaluator:
    """Scores rows on Ray actors, one per live node with CPUs; ``close`` releases them.

    Connects to ``plan.address`` (None: starts Ray on this machine). Raises
    MissingDependencyError without Ray, ClusterError when no node can take an actor.
    ``rescored`` counts candidates scored again after their actor was lost, ``lost_shares`` the
    shares that were; ``timing`` sums where the time went (:class:`Timing`).
    """

    def __init__(
        self, robot: RobotConfig, space: SearchSpace, objective: Objective, plan: EvalPlan
    ) -> None:
        self._ray = require_ray()
        self.info: ClusterInfo = connect(plan.address)
        self._args = (robot, space, objective, plan)
        self._actors: dict[str, _Actor] = {}
        self.lost_shares = 0
        self._started = False
        self._failed_starts = 0
        self.rescored = 0
        self.timing = Timing()

    @property
    def actor_cpus(self) -> list[float]:
        """The CPUs (threads) of each live actor."""
        return [actor.cpus for actor in self._ready_actors()]

    @property
    def live_workers(self) -> int:
        """Actors alive and ready."""
        return sum(actor.live for actor in self._actors.values())

    def evaluate(self, rows: Sequence[Row]) -> list[Evaluation]:
        """Score every row, in order, across the live actors; a lost actor's rows are scored
        again elsewhere."""
        if not rows:
            return []
        start = time.perf_counter()
        self._add_actors()  # Ray's node table, once a generation: part of the overhead
        self._await_ready()
        longest = 0.0
        results: list[Evaluation | None] = [None] * len(rows)
        queue = deque(self._split(_Share(0, tuple(rows)), self._ready_actors()))
        running: dict[Any, tuple[_Actor, _Share]] = {}
        while queue or running:
            for actor in self._ready_actors():
                if not queue:
                    break
                if any(a is actor for a, _ in running.values()):
                    continue
                share = queue.popleft()
                running[actor.handle.evaluate.remote(list(share.rows))] = (actor, share)
            if not running:
                self._add_actors()
                self._await_ready()
                continue
            done, _ = self._ray.wait(list(running), num_returns=1)
            actor, share = running.pop(done[0])
            try:
                scored, seconds = self._ray.get(done[0])
            except self._lost_errors():
                self._drop(actor)
                self.lost_shares += 1
                self.rescored += len(share.rows)
                queue.extend(self._split(share, self._ready_actors() or [actor]))
                continue
            results[share.start : share.start + len(share.rows)] = scored
            longest = max(longest, seconds)
            self.timing.compute_s += seconds
        timing = self.timing
        timing.wall_s += time.perf_counter() - start
        timing.critical_s += longest
        timing.candidates += len(rows)
        timing.generations += 1
        assert all(r is not None for r in results)
        return [r for r in results if r is not None]

    def baseline(self) -> Evaluation:
        """The base parameters, scored on one actor (another one if it is lost)."""
        while True:
            self._add_actors()
            self._await_ready()
            actor = self._ready_actors()[0]
            try:
                evaluation: Evaluation = self._ray.get(actor.handle.baseline.remote())
            except self._lost_errors():
                self._drop(actor)
                continue
            return evaluation

    def close(self) -> None:
        """End the actors and disconnect (stopping Ray when it was started here)."""
        for actor in self._actors.values():
            self._ray.kill(actor.handle, no_restart=True)
        self._actors.clear()
        if self.info.started_here:
            disconnect()

    def _lost_errors(self) -> tuple[type[BaseException], ...]:
        errors = self._ray.exceptions
        return (
            errors.RayActorError,
            errors.WorkerCrashedError,
            errors.NodeDiedError,
            errors.ObjectLostError,
            errors.ActorUnschedulableError,
        )

    def _ready_actors(self) -> list[_Actor]:
        return [actor for actor in self._actors.values() if actor.live]

    def _drop(self, actor: _Actor) -> None:
        actor.live = False
        self._actors.pop(actor.node_id, None)

    def _add_actors(self) -> None:
        """Start an actor on each live node with CPUs that has none."""
        from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

        worker = self._ray.remote(ShardWorker)
        for node in self._ray.nodes():
            cpus = float(node.get("Resources", {}).get("CPU", 0.0))
            node_id = node["NodeID"]
            if not node.get("Alive") or cpus < 1 or node_id in self._actors:
                continue
            handle = worker.options(
                num_cpus=cpus,
                max_restarts=0,
                scheduling_strategy=NodeAffinitySchedulingStrategy(node_id, soft=False),
            ).remote(*self._args, int(cpus))
            self._actors[node_id] = _Actor(node_id, cpus, handle, handle.ready.remote())

    def _await_ready(self) -> None:
        """Mark the actors whose model is built: the first time wait for all of them (each node
        takes a share of the first generation), later only until one is ready."""
        deadline = time.monotonic() + READY_TIMEOUT_S
        while True:
            pending = {a.ready: a for a in self._actors.values() if not a.live}
            if pending:
                waiting = not self._started or not self._ready_actors()
                done, _ = self._ray.wait(
                    list(pending), num_returns=len(pending), timeout=1.0 if waiting else 0.0
                )
                for ref in done:
                    try:
                        self._ray.get(ref)
                    except self._lost_errors() as exc:
                        self._drop(pending[ref])
                        self._failed_starts += 1
                        if self._failed_starts >= MAX_FAILED_STARTS:
                            raise ClusterError(
                                self.info.address,
                                f"{self._failed_starts} workers in a row died before they "
                                f"started; the last: {exc}",
                            ) from exc
                    else:
                        pending[ref].live = True
                        self._failed_starts = 0
            everyone = all(a.live for a in self._actors.values())
            if self._ready_actors() and (self._started or everyone):
                self._started = True
                return
            if not self._actors:
                self._add_actors()
                if not self._actors:
                    raise ClusterError(self.info.address, "no live node with a CPU is left")
            if time.monotonic() > deadline:
                raise ClusterError(
                    self.info.address, f"no worker ready after {READY_TIMEOUT_S:g} s"
                )

    def _split(self, share: _Share, actors: Sequence[_Actor]) -> list[_Share]:
        """``share`` cut into one contiguous piece per actor, sized by its CPUs."""
        total = sum(a.cpus for a in actors) or 1.0
        pieces, start, rows = [], share.start, share.rows
        taken = 0
        for i, actor in enumerate(actors):
            count = (
                len(rows) - taken if i == len(actors) - 1 else round(len(rows) * actor.cpus / total)
            )
            count = min(count, len(rows) - taken)
            if count > 0:
                pieces.append(_Share(start + taken, rows[taken : taken + count]))
                taken += count
        return pieces
