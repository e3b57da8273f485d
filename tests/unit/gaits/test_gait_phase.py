"""Every shipped gait is one formula of explicit phases: targets(t) = targets_at_phase(phi(t))."""

from __future__ import annotations

import math

import numpy as np
import pytest

from snakebot.errors import GaitError
from snakebot.gaits import make_gait
from snakebot.gaits.base import PhasedGait
from snakebot.gaits.registry import GAITS

SHIPPED = sorted(name for name in GAITS.names() if GAITS.origin(name).kind == "built-in")
PHASES = {
    "serpenoid": 1,
    "dft": 0,
    "simple": 0,
    "dft_shift": 1,
    "keyframes": 1,
    "rectilinear": 1,
    "undulation": 1,
    "miller_sidewinding": 1,
    "rolling_helix": 1,
}


def phased(name: str, joints: int = 12, **params: object) -> PhasedGait:
    gait = make_gait(name, joints, params)
    assert isinstance(gait, PhasedGait)
    return gait


@pytest.mark.parametrize("name", SHIPPED)
def test_targets_of_time_are_targets_at_the_integrated_phase(name: str) -> None:
    gait = phased(name)
    times = np.linspace(-3.0, 7.0, 61)
    phases = gait.phase0_rad + times[:, None] * gait.phase_rates_rad_s
    np.testing.assert_allclose(gait.targets(times), gait.targets_at_phase(phases), atol=1e-12)
    np.testing.assert_allclose(gait.targets(2.5), gait.targets_at_phase(phases[33]), atol=1e-12)
    assert gait.phase_rates_rad_s.size == PHASES.get(name, 2)


def test_compound_phases_move_the_even_and_odd_waves_separately() -> None:
    gait = phased("sidewinding")
    base = gait.targets_at_phase([0.3, 0.3])
    moved = gait.targets_at_phase([0.3 + math.pi, 0.3])
    np.testing.assert_allclose(moved[1::2], base[1::2])  # odd (pitch) joints untouched
    np.testing.assert_allclose(moved[0::2], -base[0::2], atol=1e-12)  # even wave half a turn on


def test_a_full_phase_turn_is_one_cycle_of_every_periodic_gait() -> None:
    for name in ("serpenoid", "sidewinding", "dft_shift", "keyframes"):
        gait = phased(name)
        phase = np.full(gait.phase_rates_rad_s.size, 0.4)
        np.testing.assert_allclose(
            gait.targets_at_phase(phase + 2 * math.pi), gait.targets_at_phase(phase), atol=1e-9
        )


def test_dft_shift_phase_of_one_joint_rolls_the_pose_by_one_joint() -> None:
    gait = phased("dft_shift", 8)
    pose = gait.targets_at_phase([0.0])
    np.testing.assert_allclose(
        gait.targets_at_phase([2 * math.pi / 8]), np.roll(pose, 1), atol=1e-12
    )


@pytest.mark.parametrize("bad", [[0.1, 0.2], [[0.1]] * 2 + [[0.2, 0.3]], [math.nan], "x"])
def test_a_wrong_phase_names_the_expected_shape(bad: object) -> None:
    with pytest.raises(GaitError, match=r"serpenoid: (expected phases of shape \(1,\)|phases)"):
        phased("serpenoid").targets_at_phase(bad)  # type: ignore[arg-type]
