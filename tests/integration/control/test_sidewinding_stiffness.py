"""Sidewinding's direction depends on servo stiffness (docs/physics.md; measured by
tools/sidewinding_stiffness.py)."""

from __future__ import annotations

import pytest

from tools.sidewinding_stiffness import sidewind

pytestmark = pytest.mark.slow


def test_stiff_servos_sidewind_in_a_circle_soft_ones_go_straight_sideways() -> None:
    soft = sidewind(640)
    stiff = sidewind(1280)
    assert abs(float(soft["turn_deg"])) < 20  # type: ignore[arg-type]
    assert 85 < float(soft["heading_deg"]) < 105  # type: ignore[arg-type]
    assert float(stiff["turn_deg"]) > 90  # type: ignore[arg-type]
    assert float(stiff["distance_m"]) < 0.8 * float(soft["distance_m"])  # type: ignore[arg-type]
