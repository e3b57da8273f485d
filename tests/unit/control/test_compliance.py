"""Gait-based compliance (snakebot.control.compliance): the gait gives way where the servos push
hard, springs back once the push stops, and refuses a backend that cannot measure the push."""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.backends.chain import ServoChainBackend
from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.control.compliance import (
    ComplianceSettings,
    CompliantGait,
    StallMeter,
    check_torque_sensing,
    windows_matrix,
)
from snakebot.control.cycle import CycleRecord
from snakebot.errors import ConfigError
from snakebot.gaits import make_gait
from snakebot.types import JointState

STALL_NM = 1.5
PERIOD_S = 0.01


def _gait(joints: int = 8) -> CompliantGait:
    return CompliantGait(make_gait("serpenoid", joints, {}), STALL_NM)


def _record(
    effort_nm: np.ndarray, *, velocity: float = 0.0, scored: bool = True, time_s: float = 0.0
) -> CycleRecord:
    n = effort_nm.shape[0]
    state = JointState(time_s, np.zeros(n), np.full(n, velocity), effort_nm)
    return CycleRecord(
        cycle=1,
        gait_time_s=time_s,
        target_rad=np.zeros(n),
        command_rad=np.zeros(n),
        state=state,
        body=None,
        amplitude=1.0,
        scored=scored,
        period_s=PERIOD_S,
        overrun=False,
        achieved_rate_hz=100.0,
    )


def _push(gait: CompliantGait, seconds: float, where: slice, fraction: float) -> None:
    """Cycles of the servos in ``where`` pushing with ``fraction`` of stall torque towards
    the gait's own target (a peg holding the joint back from it)."""
    for k in range(round(seconds / PERIOD_S)):
        t = k * PERIOD_S
        raw = gait.gait.command(t)
        gait.command(t)
        effort = np.zeros(gait.joint_count)
        effort[where] = fraction * STALL_NM * np.sign(raw[where])
        gait.observe(_record(effort, time_s=t))


def test_windows_cover_the_body_head_to_tail() -> None:
    matrix = windows_matrix(8, 4)
    assert matrix.shape == (8, 4)
    np.testing.assert_allclose(matrix.sum(axis=1), 1.0)
    assert matrix[0].argmax() == 0 and matrix[-1].argmax() == 3
    assert windows_matrix(3, 6).shape == (3, 3)  # never more windows than joints
    np.testing.assert_array_equal(windows_matrix(5, 1), np.ones((5, 1)))


def test_torque_inside_the_dead_band_bends_nothing() -> None:
    gait = _gait()
    _push(gait, 2.0, slice(None), 0.25)  # ordinary locomotion torque, under the 0.3 dead band
    np.testing.assert_array_equal(gait.amplitude_scale, 1.0)
    np.testing.assert_array_equal(gait.offset_rad, 0.0)
    np.testing.assert_allclose(gait.command(0.7), gait.gait.command(0.7))


def test_a_hard_push_at_the_head_flattens_the_head_and_springs_back() -> None:
    gait = _gait()
    _push(gait, 1.0, slice(0, 2), 0.9)  # the head's two servos held near stall
    head, tail = gait.amplitude_scale[0], gait.amplitude_scale[-1]
    assert head < 0.8, gait.amplitude_scale
    assert tail > 0.97, gait.amplitude_scale  # the far end of the body keeps its wave
    t = 0.55
    raw, shaped = gait.gait.command(t), gait.command(t)
    assert abs(shaped[0] - gait.windows[0] @ gait.offset_rad) < abs(raw[0])
    assert gait.summary()["lowest_amplitude_scale"][0] == pytest.approx(head, abs=1e-4)  # type: ignore[index]
    _push(gait, 2.0, slice(0, 2), 0.0)  # the push stops
    np.testing.assert_allclose(gait.amplitude_scale, 1.0, atol=1e-2)
    np.testing.assert_allclose(gait.offset_rad, 0.0, atol=1e-2)
    assert gait.summary()["lowest_amplitude_scale"][0] == pytest.approx(head, abs=1e-4)  # type: ignore[index]


def test_the_parameters_stay_inside_their_bounds_and_reset() -> None:
    settings = ComplianceSettings(amplitude_range=(0.5, 1.2), offset_limit_rad=0.1)
    gait = CompliantGait(make_gait("serpenoid", 8, {}), STALL_NM, settings)
    for k in range(300):  # a constant one-sided push, far past stall
        gait.command(k * PERIOD_S)
        gait.observe(_record(np.full(8, 3.0 * STALL_NM), time_s=k * PERIOD_S))
    assert gait.amplitude_scale.min() >= 0.5 and gait.amplitude_scale.max() <= 1.2
    assert np.abs(gait.offset_rad).max() == pytest.approx(0.1)
    assert (gait.offset_rad < 0).all()  # a positive push moves the command the negative way
    gait.reset()
    np.testing.assert_array_equal(gait.amplitude_scale, 1.0)
    np.testing.assert_array_equal(gait.offset_rad, 0.0)
    np.testing.assert_allclose(gait.targets(np.array([0.0, 0.3])), gait.gait.targets([0.0, 0.3]))


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("windows", 0),
        ("dead_band", 1.0),
        ("amplitude_gain", -1.0),
        ("return_s", 0.0),
        ("amplitude_range", (1.1, 1.5)),
        ("offset_limit_rad", float("nan")),
    ],
)
def test_bad_settings_name_the_field(field: str, value: object) -> None:
    with pytest.raises(ConfigError, match=field) as caught:
        ComplianceSettings(**{field: value})  # type: ignore[arg-type]
    assert "expected" in str(caught.value)


def test_a_gait_without_a_stall_torque_is_refused() -> None:
    with pytest.raises(ConfigError, match="stall_torque_nm"):
        CompliantGait(make_gait("serpenoid", 8, {}), 0.0)


def test_the_stall_meter_counts_pushing_without_moving_in_scored_cycles() -> None:
    meter = StallMeter(STALL_NM, no_load_speed_rad_s=6.0)
    pushing = np.array([0.8, 0.1, -0.9, 0.0]) * STALL_NM
    meter(_record(pushing))  # two servos stalled for one cycle
    meter(_record(pushing, velocity=1.0))  # moving: not a stall
    meter(_record(pushing, scored=False))  # the ramp-out: not counted
    summary = meter.summary()
    assert summary["servo_stall_s"] == pytest.approx(2 * PERIOD_S)
    assert summary["peak_servo_torque_nm"] == pytest.approx(0.9 * STALL_NM)


def test_only_a_backend_that_measures_torque_is_accepted() -> None:
    check_torque_sensing(TwinBackend(load_robot("snake8")))
    check_torque_sensing(ServoChainBackend(load_robot("snake12-sts3215"), port="/dev/null"))
    for name in ("snake8", "snake12-ax12a"):  # XL430 and AX-12A: Present Load, no current
        with pytest.raises(ConfigError, match=r"^compliance") as caught:
            check_torque_sensing(ServoChainBackend(load_robot(name), port="/dev/null"))
        assert "Present Current" in str(caught.value)
        assert "ServoChainBackend" in str(caught.value)
