"""The GA of "Using a Genetic Algorithm to Implement Pose Tracking" (Wilson), over keyframe poses.

The genome is the keyframe poses (P poses of N angles; with ``mirror`` half a cycle). Each
generation grows the population by pose-level crossover of random parents (children may mutate:
one pose, two joints, new random angles), evaluates the newcomers, then culls back to the
population size by loss, letting no duplicate genome survive. When the best has not improved
for ``stagnation`` generations, a period of forced evolution replaces crossover with heavy
mutation and fresh random genomes. Flipped or airborne candidates are cut short by the engine.
No GA library is used: DEAP or PyGAD would supply only the loop, while every operator here is
the report's own.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snakebot.errors import ConfigError
from snakebot.tuning.problem import SearchProblem
from snakebot.tuning.trace import FloatArray


@dataclass(frozen=True)
class Generation:
    """One generation: evaluations so far, best and median loss of the population, its mode."""

    index: int
    evaluations: int
    best_loss: float
    median_loss: float
    forced: bool


@dataclass(frozen=True)
class GaSettings:
    """Population size, growth factor per generation, mutation chance and stagnation patience."""

    population: int = 16
    growth: float = 2.0
    mutation_rate: float = 0.3
    stagnation: int = 3
    forced_generations: int = 2
    improvement: float = 1e-3


def genetic_search(
    problem: SearchProblem, budget: int, seed: int, settings: GaSettings | None = None
) -> list[Generation]:
    """Evolve joint poses (keyframes') for at most ``budget`` evaluations; the base poses are in
    the first generation. ConfigError unless every coordinate of the space is a pose angle."""
    cfg = settings or GaSettings()
    space = problem.space
    if not space.dims or not all(d.pose_angle for d in space.dims):
        raise ConfigError(
            "method",
            "ga",
            "the GA evolves lists of joint poses: search only a gait's pose list "
            "(e.g. params poses of gait keyframes; `snakebot gaits` marks such parameters)",
        )
    joints = problem.robot.joint_count
    if len(space.dims) % joints:
        raise ConfigError("params", "poses", f"expected whole poses of {joints} angles")
    rng = np.random.default_rng(seed)
    ops = _Operators(rng, space.lower, space.upper, joints)
    size = min(cfg.population, budget)
    genomes = [space.start()] + [ops.random() for _ in range(size - 1)]
    losses = [e.loss for e in problem.evaluate(genomes)]
    history = [Generation(0, problem.evaluations, min(losses), float(np.median(losses)), False)]
    stale, forced_left = 0, 0
    while problem.evaluations < budget:
        room = budget - problem.evaluations
        count = min(max(1, int(size * (cfg.growth - 1.0))), room)
        forced = forced_left > 0
        if forced:
            children = [ops.heavy_mutation(genomes[i % len(genomes)]) for i in range(count // 2)]
            children += [ops.random() for _ in range(count - len(children))]
            forced_left -= 1
        else:
            children = [ops.child(genomes, cfg.mutation_rate) for _ in range(count)]
        scored = problem.evaluate(children)
        before = min(losses)
        genomes, losses = _cull(genomes + children, losses + [e.loss for e in scored], size)
        improved = min(losses) < before - cfg.improvement * max(abs(before), 1e-9)
        stale = 0 if improved else stale + 1
        if stale >= cfg.stagnation and not forced:
            forced_left, stale = cfg.forced_generations, 0
        history.append(
            Generation(
                len(history), problem.evaluations, min(losses), float(np.median(losses)), forced
            )
        )
    return history


class _Operators:
    """Random genomes, pose-level crossover and the report's two-joint mutation."""

    def __init__(self, rng: np.random.Generator, lower: FloatArray, upper: FloatArray, n: int):
        self.rng, self.lower, self.upper, self.joints = rng, lower, upper, n

    def random(self) -> FloatArray:
        return self.rng.uniform(self.lower, self.upper)

    def child(self, genomes: list[FloatArray], mutation_rate: float) -> FloatArray:
        a, b = self.rng.choice(len(genomes), size=2, replace=len(genomes) < 2)
        poses_a = genomes[a].reshape(-1, self.joints)
        poses_b = genomes[b].reshape(-1, self.joints)
        pick = self.rng.random(len(poses_a)) < 0.5
        child = np.where(pick[:, None], poses_a, poses_b).ravel()
        return self.mutate(child) if self.rng.random() < mutation_rate else child

    def mutate(self, genome: FloatArray) -> FloatArray:
        """One random pose gets two of its joints set to new random angles within the bounds."""
        out = genome.copy()
        pose = self.rng.integers(len(out) // self.joints)
        for joint in self.rng.choice(self.joints, size=min(2, self.joints), replace=False):
            i = pose * self.joints + joint
            out[i] = self.rng.uniform(self.lower[i], self.upper[i])
        return out

    def heavy_mutation(self, genome: FloatArray) -> FloatArray:
        out = genome
        for _ in range(1 + len(genome) // self.joints):
            out = self.mutate(out)
        return out


def _cull(
    genomes: list[FloatArray], losses: list[float], size: int
) -> tuple[list[FloatArray], list[float]]:
    """The ``size`` lowest-loss genomes, no two identical."""
    kept: list[FloatArray] = []
    kept_losses: list[float] = []
    seen: set[bytes] = set()
    for i in np.argsort(losses, kind="stable"):
        key = np.round(genomes[i], 9).tobytes()
        if key in seen:
            continue
        seen.add(key)
        kept.append(genomes[i])
        kept_losses.append(losses[i])
        if len(kept) == size:
            break
    return kept, kept_losses
