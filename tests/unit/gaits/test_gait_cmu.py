"""The CMU parity gaits: conical sidewinding, the rolling helix and head-look, without physics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from snakebot.errors import GaitError
from snakebot.gaits import make_gait
from snakebot.gaits.cmu import (
    HeadLookGait,
    RollingHelixGait,
    body_chassis,
    helix_amplitude,
    solve_head,
    taper_scale,
)

TIMES = np.linspace(0.0, 4.0, 41)
AXES12 = tuple("yaw" if i % 2 == 0 else "pitch" for i in range(12))


def test_conical_sidewinding_with_taper_zero_is_sidewinding_to_the_bit() -> None:
    plain = make_gait("sidewinding", 12, {"amplitude_even": 0.5, "phase_shift": -math.pi / 4})
    conical = make_gait(
        "conical_sidewinding",
        12,
        {"taper": 0.0, "amplitude_even": 0.5, "phase_shift": -math.pi / 4},
    )
    assert np.array_equal(conical.targets(TIMES), plain.targets(TIMES))


def test_the_taper_scales_the_waves_linearly_head_to_tail_about_the_middle() -> None:
    plain = make_gait("sidewinding", 12).targets(TIMES)
    conical = make_gait("conical_sidewinding", 12, {"taper": 0.8}).targets(TIMES)
    scale = taper_scale(12, 0.8)
    np.testing.assert_allclose(conical, plain * scale, atol=1e-12)
    assert scale[0] > 1.0 > scale[-1]  # taper > 0: bigger head waves
    np.testing.assert_allclose(np.diff(scale), -0.8 / 12)
    assert scale.mean() == pytest.approx(1.0)
    flipped = make_gait("conical_sidewinding", 12, {"taper": -0.8}).targets(TIMES)
    np.testing.assert_allclose(flipped, plain * scale[::-1], atol=1e-12)


def test_a_taper_that_turns_a_wave_over_is_refused() -> None:
    with pytest.raises(GaitError, match="taper"):
        make_gait("conical_sidewinding", 12, {"taper": 2.5})


def test_helix_amplitude_is_cmus_formula_and_tightens_on_thinner_poles() -> None:
    r, p, m = 0.072, 0.04, 0.065
    k, tau = r / (r * r + p * p), p / (r * r + p * p)
    assert helix_amplitude(r, p, m) == pytest.approx(2 * k * math.sin(tau * m) / tau)
    # Above r = p (the curvature r/(r^2+p^2) peaks there) a thinner pole coils tighter.
    assert helix_amplitude(0.05, p, m) > helix_amplitude(0.072, p, m) > helix_amplitude(0.2, p, m)
    assert helix_amplitude(r, 0.0, m) == pytest.approx(2 * m / r)  # a flat ring: 2*m*curvature
    with pytest.raises(GaitError):
        helix_amplitude(0.0, p, m)


def test_rolling_helix_takes_its_amplitude_from_the_pole_and_rolls_by_phase() -> None:
    gait = make_gait("rolling_helix", 12, {"pole_radius_m": 0.08})
    assert isinstance(gait, RollingHelixGait)
    expected = helix_amplitude(0.08 + 0.022, 0.04, 0.065)
    assert gait.amplitude_rad == pytest.approx(expected)
    q = gait.targets(TIMES)
    # Every joint swings through +-A once a roll (4 s at pi/2 rad/s), yaw a quarter turn
    # ahead of pitch (cos against sin), so each yaw/pitch pair turns the body about its axis.
    np.testing.assert_allclose(np.abs(q).max(axis=0), expected, rtol=0.01)
    lags = 0.04 / (0.102**2 + 0.04**2) * 0.065 * np.arange(12)  # tau * m per joint
    np.testing.assert_allclose(gait.targets(0.0)[0::2], expected * np.cos(lags[0::2]), atol=1e-12)
    np.testing.assert_allclose(gait.targets(0.0)[1::2], expected * np.sin(lags[1::2]), atol=1e-12)
    one_turn = gait.targets(np.array([0.3, 0.3 + 2 * math.pi / (math.pi / 2)]))
    np.testing.assert_allclose(one_turn[0], one_turn[1], atol=1e-9)


def test_rolling_helix_stays_inside_the_joint_limits() -> None:
    lower, upper = np.full(12, -0.5), np.full(12, 0.5)
    gait = make_gait("rolling_helix", 12, {"pole_radius_m": 0.0}, lower_rad=lower, upper_rad=upper)
    q = gait.targets(TIMES)
    assert q.min() >= -0.48 - 1e-12 and q.max() <= 0.48 + 1e-12


def test_solve_head_reaches_a_yaw_pitch_orientation_exactly() -> None:
    axes = AXES12[:4]
    lower, upper = np.full(4, -1.5), np.full(4, 1.5)
    c, s = math.cos(0.4), math.sin(0.4)
    want = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])  # a pure yaw of 0.4 rad
    q = solve_head(axes, want, lower, upper)
    assert q[0] + q[2] == pytest.approx(0.4, abs=1e-3)
    assert abs(q[1]) < 1e-3 and abs(q[3]) < 1e-3


def test_body_chassis_of_a_straight_body_is_the_modules_frame() -> None:
    bent = np.zeros(12)
    bent[4::2] = 0.3  # a planar yaw arc behind the head: its least-extent axis is z
    chassis = body_chassis(AXES12, bent, 4)
    assert chassis[:, 2] @ np.array([0.0, 0.0, 1.0]) == pytest.approx(1.0)
    assert abs(np.linalg.det(chassis) - 1.0) < 1e-9


def test_head_look_leaves_the_body_joints_to_the_base_gait() -> None:
    base = make_gait("sidewinding", 12)
    look = make_gait("head_look", 12, {"pan_rad": 0.3})
    assert isinstance(look, HeadLookGait)
    np.testing.assert_array_equal(look.targets(TIMES)[:, 4:], base.targets(TIMES)[:, 4:])
    assert not np.allclose(look.targets(TIMES)[:, :4], base.targets(TIMES)[:, :4])
    assert np.abs(look.targets(TIMES)[:, :4]).max() <= math.pi / 2 + 1e-12  # the limits


def test_head_look_on_a_flat_body_just_pans() -> None:
    flat = make_gait("head_look", 12, {"base": "lateral_undulation", "pan_rad": 0.4})
    q = flat.targets(TIMES)
    # Lateral undulation leaves the pitch joints at 0: the body is flat, the head only yaws.
    np.testing.assert_allclose(q[:, 1:4:2], 0.0, atol=1e-6)


def test_head_look_needs_six_joints() -> None:
    with pytest.raises(GaitError, match="at least 6 joints"):
        make_gait("head_look", 5)
