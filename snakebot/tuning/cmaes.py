"""CMA-ES (the ``cma`` package, Hansen's reference implementation) over the search box.

The search runs in the unit cube (each bound box edge mapped to [0, 1]) so one step size fits
every parameter; a whole population is evaluated as one parallel batch.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from snakebot.errors import ConfigError, MissingDependencyError
from snakebot.tuning.problem import SearchProblem

INSTALL = "pip install 'snakebot[tune]'"


def require_cma() -> Any:
    """The ``cma`` module; MissingDependencyError with the install command when it is missing."""
    try:
        import cma
    except ImportError as exc:
        raise MissingDependencyError(
            f"CMA-ES (method cmaes) needs the cma package: {INSTALL}"
        ) from exc
    return cma


def default_popsize(dims: int, workers: int) -> int:
    """CMA-ES's default 4 + 3 ln(D), rounded up to a multiple of the worker count."""
    size = 4 + int(3 * np.log(dims))
    return int(-(-size // workers) * workers)


def cmaes_search(
    problem: SearchProblem,
    budget: int,
    seed: int,
    *,
    popsize: int | None = None,
    sigma0: float = 0.25,
) -> list[float]:
    """Minimise the loss within ``budget`` evaluations from the base point; returns the best loss
    after each generation. Stops early when CMA-ES converges."""
    cma = require_cma()
    space = problem.space
    dims = len(space.dims)
    if dims < 2:
        raise ConfigError("params", space.names[0], "CMA-ES needs 2 or more; use method grid")
    size = popsize or default_popsize(dims, problem.plan.workers)
    if size > budget:
        raise ConfigError("budget", str(budget), f"less than one CMA-ES population ({size})")
    span = space.upper - space.lower
    start = (space.start() - space.lower) / span
    options = {
        "bounds": [0.0, 1.0],
        "popsize": size,
        "seed": seed + 1,  # cma treats 0 as "seed from the clock"
        "maxfevals": budget,
        "verbose": -9,
    }
    strategy = cma.CMAEvolutionStrategy(np.clip(start, 0.0, 1.0).tolist(), sigma0, options)
    best: list[float] = []
    while not strategy.stop() and problem.evaluations + size <= budget:
        unit = strategy.ask()
        scored = problem.evaluate([space.lower + np.asarray(u) * span for u in unit])
        strategy.tell(unit, [e.loss for e in scored])
        best.append(min(e.loss for e in problem.history))
    return best
