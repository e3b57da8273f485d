"""Finite backward friction for Miller's scales (issue 23): ratio 1 is no scales, inf is Miller.

The ratio r makes the scales resist backward sliding with r times the floor's friction: the rule
takes off at most (r - 1) mu N h / m of a point's backward speed per step. At r = 1 it takes off
nothing, the body of ``directional off``; as r grows the worm crawls farther, up to Miller's
ideal ratchet (r = inf, the default); the C stepper and the numpy loop agree.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from snakebot.backends.softbody import SoftBodyBackend
from snakebot.config.body_loader import load_body
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.errors import ConfigError
from snakebot.gaits import make_gait

WORM = load_body("worm")


def crawl(**options: object) -> tuple[float, np.ndarray]:
    """1.5 s of rectilinear progression: (distance m, the final qpos and qvel)."""
    metrics = RunMetrics(WORM.joint_count, WORM.body_length_m, WORM.total_mass_kg)
    with SoftBodyBackend(WORM, **options) as soft:  # type: ignore[arg-type]
        result = run_gait(
            soft,
            make_gait("rectilinear", WORM.joint_count),
            SafetyLayer.for_robot(WORM),
            RunPlan(duration_s=1.5, ramp_out=False),
            metrics,
        )
        state = np.concatenate((soft.data.qpos, soft.data.qvel))
    return float(result.summary["distance_m"]), state  # type: ignore[arg-type]


def test_ratio_one_is_the_body_without_scales_and_inf_is_millers_rule() -> None:
    no_scales = crawl(directional=False)[1]
    assert np.array_equal(crawl(backward_ratio=1.0)[1], no_scales)
    assert np.array_equal(crawl(backward_ratio=math.inf)[1], crawl()[1])


def test_the_worm_crawls_farther_as_the_backward_friction_grows() -> None:
    distances = [crawl(backward_ratio=r)[0] for r in (1.0, 2.0, 8.0, math.inf)]
    assert distances == sorted(distances)
    assert distances[1] > 3 * distances[0]
    assert distances[2] > 0.9 * distances[3]


def test_c_and_numpy_apply_the_finite_rule_alike() -> None:
    c = crawl(backward_ratio=2.0, implementation="c")[1]
    numpy = crawl(backward_ratio=2.0, implementation="numpy")[1]
    np.testing.assert_allclose(c, numpy, rtol=0, atol=1e-12)


def test_a_ratio_below_one_is_refused() -> None:
    with pytest.raises(ConfigError, match="backward_ratio"):
        SoftBodyBackend(WORM, backward_ratio=0.5)


def test_the_ratchet_bound_of_one_segment_is_its_stroke_and_millers_worm_nears_it() -> None:
    """One segment pushing its head out and pulling its tail in, never sliding back, advances
    its full stroke 2 A L0 per cycle; the six-segment worm's bound is what the table compares
    against (docs/soft-bodies.md)."""
    from tools.soft_backward_friction import ratchet_bound_m

    gait = make_gait("rectilinear", 3, {"amplitude": 0.25})
    assert ratchet_bound_m(gait, 1, 0.02) == pytest.approx(2 * 0.25 * 0.02, rel=1e-6)  # type: ignore[arg-type]
    worm = make_gait("rectilinear", WORM.joint_count)
    bound = ratchet_bound_m(worm, WORM.lattice.segments, WORM.lattice.segment_length_m)  # type: ignore[arg-type]
    assert 2 * 0.3 * 0.02 < bound < 6 * 2 * 0.3 * 0.02
