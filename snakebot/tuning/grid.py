"""Grid search, the seed's method ("Serpentile Locomotion": omega x phase_lag, Figure 10)."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from snakebot.errors import ConfigError
from snakebot.tuning.problem import SearchProblem
from snakebot.tuning.trace import FloatArray


@dataclass(frozen=True)
class GridResult:
    """The axes (one array per dimension) and the evaluations' indices in C order over them."""

    axes: tuple[FloatArray, ...]
    first_index: int

    @property
    def shape(self) -> tuple[int, ...]:
        """Points per dimension."""
        return tuple(len(axis) for axis in self.axes)


def points_per_dim(budget: int, dims: int) -> int:
    """The most points per dimension a full grid can have within ``budget`` evaluations."""
    count = max(2, int(budget ** (1.0 / dims) + 0.5))
    while count > 2 and count**dims > budget:
        count -= 1
    return count


def grid_search(problem: SearchProblem, budget: int, chunk: int = 20) -> GridResult:
    """Evaluate a full grid with ``points_per_dim(budget, D)`` evenly spaced points per bound box
    edge (bounds included), ``chunk`` candidates per parallel batch."""
    space = problem.space
    dims = len(space.dims)
    if dims > 4:
        raise ConfigError("method", "grid", f"a grid over {dims} parameters is too big; use cmaes")
    count = points_per_dim(budget, dims)
    if count**dims > budget:
        raise ConfigError(
            "budget", str(budget), f"a grid over {dims} parameters needs at least {2**dims}"
        )
    axes = tuple(
        np.linspace(lo, hi, count) for lo, hi in zip(space.lower, space.upper, strict=True)
    )
    points = [np.array(p) for p in itertools.product(*axes)]
    first = problem.evaluations
    for start in range(0, len(points), chunk):
        problem.evaluate(points[start : start + chunk])
    return GridResult(axes, first)
