from __future__ import annotations

import numpy as np

from snakebot.tuning.genetic import _cull, _Operators
from snakebot.tuning.grid import points_per_dim


def operators(seed: int = 0) -> _Operators:
    return _Operators(np.random.default_rng(seed), np.full(6, -0.5), np.full(6, 0.5), 3)


def test_crossover_takes_whole_poses_from_the_parents() -> None:
    ops = operators()
    a, b = np.zeros(6), np.ones(6) * 0.3
    for _ in range(20):
        child = ops.child([a, b], mutation_rate=0.0).reshape(2, 3)
        for pose in child:
            assert np.all(pose == 0.0) or np.all(pose == 0.3)


def test_mutation_changes_two_joints_of_one_pose_within_bounds() -> None:
    ops = operators(1)
    genome = np.zeros(6)
    for _ in range(20):
        changed = np.flatnonzero(ops.mutate(genome) != genome)
        assert 1 <= len(changed) <= 2 and len(set(changed // 3)) == 1
    assert np.all(np.abs(ops.heavy_mutation(genome)) <= 0.5)


def test_culling_keeps_the_best_and_no_duplicates() -> None:
    genomes = [np.full(6, v) for v in (0.1, 0.1, 0.2, 0.3)]
    kept, losses = _cull(genomes, [1.0, 1.0, 3.0, 2.0], 3)
    assert losses == [1.0, 2.0, 3.0]
    assert [g[0] for g in kept] == [0.1, 0.3, 0.2]


def test_grid_size_fits_the_budget() -> None:
    assert points_per_dim(100, 2) == 10
    assert points_per_dim(99, 2) == 9
    assert points_per_dim(9, 2) == 3
    assert points_per_dim(30, 3) == 3
