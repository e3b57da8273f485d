"""The compiled stepping loop (friction_c) against the numpy rule it replaces."""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.backends.softbody import SoftBodyBackend
from snakebot.config.body_loader import load_body
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait


def _run(robot: str, gait: str, implementation: str) -> tuple[SoftBodyBackend, np.ndarray]:
    body = load_body(robot)
    metrics = RunMetrics(body.joint_count, body.body_length_m, body.total_mass_kg)
    plan = RunPlan(duration_s=1.5, rate_hz=100.0, ramp_out=False)
    backend = SoftBodyBackend(body, implementation=implementation)  # type: ignore[arg-type]
    with backend:
        run_gait(
            backend, make_gait(gait, body.joint_count), SafetyLayer.for_robot(body), plan, metrics
        )
        velocity = backend.read_state().velocity_rad_s.copy()
        state = np.concatenate((backend.data.qpos, backend.data.qvel, velocity))
    return backend, state


@pytest.mark.parametrize(("robot", "gait"), [("snake", "undulation"), ("worm", "rectilinear")])
def test_c_and_numpy_rules_step_the_same_body(robot: str, gait: str) -> None:
    c, c_state = _run(robot, gait, "c")
    numpy, numpy_state = _run(robot, gait, "numpy")
    assert c.implementation == "c"
    assert numpy.implementation == "numpy"
    # Same points projected on every step, and the same state: bit for bit on this machine (the
    # C adds its dot products in einsum's order); 1e-12 allows another numpy's SIMD order.
    assert c.friction_rule.projected == numpy.friction_rule.projected > 0
    np.testing.assert_allclose(c_state, numpy_state, rtol=0, atol=1e-12)
