"""Cross-check MuJoCo's soft body against a plain numpy integrator of Miller's model."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from snakebot.backends.softbody import SoftBodyBackend
from snakebot.config.body import BodyConfig
from snakebot.config.body_loader import load_body
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from tests.integration.softbody.reference_integrator import run_reference

DURATION_S = 5.0


def _worm() -> BodyConfig:
    # Without the bulge, Miller's mechanism is the directional rule alone.
    worm = load_body("worm")
    return replace(worm, muscles=replace(worm.muscles, volume_preservation=False))


def _mujoco_displacement(body: BodyConfig, directional: bool) -> np.ndarray:
    gait = make_gait("rectilinear", body.joint_count)
    metrics = RunMetrics(body.joint_count, body.body_length_m, body.total_mass_kg)
    with SoftBodyBackend(body, directional=directional) as backend:
        run_gait(
            backend,
            gait,
            SafetyLayer.for_robot(body),
            RunPlan(DURATION_S, ramp_out=False),
            metrics,
        )
    assert metrics.start_com is not None and metrics.end_com is not None
    return metrics.end_com - metrics.start_com  # type: ignore[no-any-return]


@pytest.mark.slow
def test_rectilinear_progression_needs_the_directional_rule_in_both_integrators() -> None:
    body = _worm()
    gait = make_gait("rectilinear", body.joint_count)
    reference = {
        rule: run_reference(body, gait, duration_s=DURATION_S, directional=rule).displacement
        for rule in (True, False)
    }
    mujoco = {rule: _mujoco_displacement(body, rule) for rule in (True, False)}
    for name, runs in (("reference", reference), ("mujoco", mujoco)):
        with_rule, without = (float(np.linalg.norm(runs[rule][:2])) for rule in (True, False))
        assert runs[True][0] > 0.9 * with_rule, f"{name}: the worm must crawl head first (+x)"
        assert with_rule > 0.1, f"{name}: {with_rule:.3f} m in {DURATION_S} s is no crawl"
        assert with_rule > 5 * without, f"{name}: {with_rule:.3f} m vs {without:.3f} m"
    # Different floors (impulse vs soft contact), same mechanism: speeds agree within 2x.
    ratio = mujoco[True][0] / reference[True][0]
    assert 0.5 < ratio < 2.0
