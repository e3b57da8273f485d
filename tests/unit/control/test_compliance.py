"""Gait-based compliance (snakebot.control.compliance): the gait gives way where the servos push
hard, springs back once the push stops, and refuses a backend that cannot measure the push."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
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
from snakebot.gaits.base import FloatArray, Gait
from snakebot.types import JointState

STALL_NM = 1.5
PERIOD_S = 0.01


def _gait(joints: int = 8) -> CompliantGait:
    return CompliantGait(make_gait("serpenoid", joints, {}), STALL_NM)


PHASE_ONLY = ComplianceSettings(amplitude_gain=0.0, offset_gain=0.0, phase_gain=30.0)


def _phase_gait(settings: ComplianceSettings = PHASE_ONLY) -> CompliantGait:
    return CompliantGait(make_gait("serpenoid", 8, {}), STALL_NM, settings)


def _slope(gait: CompliantGait, t: float) -> np.ndarray:
    """The wrapped gait's time derivative (N,) rad/s at ``t``."""
    ahead, behind = gait.gait.targets(np.array([t + 1e-5, t - 1e-5]))
    return (ahead - behind) / 2e-5  # type: ignore[no-any-return]


def _lagging_push(gait: CompliantGait, seconds: float, where: slice, fraction: float) -> None:
    """Cycles of the servos in ``where`` held back behind the travelling wave: each pushes
    with ``fraction`` of stall torque the way its own target is moving (it lags it)."""
    for k in range(round(seconds / PERIOD_S)):
        t = k * PERIOD_S
        gait.command(t)
        effort = np.zeros(gait.joint_count)
        effort[where] = fraction * STALL_NM * np.sign(_slope(gait, t)[where])
        gait.observe(_record(effort, time_s=t))


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


def test_a_joint_held_behind_the_wave_plays_its_window_late_and_springs_back() -> None:
    gait = _phase_gait()
    assert gait.shifts_phase
    _lagging_push(gait, 1.0, slice(0, 2), 0.9)
    head, tail = gait.phase_rad[0], gait.phase_rad[-1]
    assert head < -0.05, gait.phase_rad  # the head runs late, towards where it is held
    assert abs(tail) < 0.2 * abs(head), gait.phase_rad  # the far end keeps its timing
    assert gait.shift_s()[0] < 0.0
    for t in (0.3, 0.8, 1.23, 1.7):  # the head's command is behind its own target's motion
        raw, shaped, slope = gait.gait.command(t), gait.command(t), _slope(gait, t)
        assert (shaped[0] - raw[0]) * slope[0] < 0.0, (t, shaped, raw)
    largest = gait.summary()["largest_phase_rad"]
    assert largest[0] == pytest.approx(abs(head), abs=1e-3)  # type: ignore[index]
    _lagging_push(gait, 2.0, slice(0, 2), 0.0)  # the push stops
    np.testing.assert_allclose(gait.phase_rad, 0.0, atol=1e-2)
    np.testing.assert_allclose(gait.command(0.7), gait.gait.command(0.7), atol=1e-2)
    assert gait.summary()["largest_phase_rad"] == largest  # the record of how far it went


def test_every_phase_step_moves_the_command_against_the_torque() -> None:
    rng = np.random.default_rng(3)
    for _ in range(20):
        gait = _phase_gait()
        gait.phase_rad[:] = rng.uniform(-0.3, 0.3, gait.phase_rad.size)
        t = float(rng.uniform(0.0, 4.0))
        before = gait.command(t)
        effort = rng.uniform(-1.0, 1.0, 8) * STALL_NM
        gait.observe(_record(effort, time_s=t))
        excess = np.sign(effort) * np.maximum(np.abs(effort) / STALL_NM - 0.3, 0.0)
        moved = gait.command(t) - before
        assert excess @ moved < 0.0  # the push eases: the command gives way to it


def test_the_phase_stays_inside_its_bound_and_resets() -> None:
    settings = ComplianceSettings(amplitude_gain=0.0, phase_gain=500.0, phase_limit_rad=0.2)
    gait = _phase_gait(settings)
    _lagging_push(gait, 3.0, slice(None), 3.0)  # far past stall, the whole body held back
    assert np.abs(gait.phase_rad).max() <= 0.2
    assert np.abs(gait.largest_phase_rad).max() == pytest.approx(0.2)
    shift = gait.shift_s()
    assert np.abs(shift).max() <= 0.2 / (2 * np.pi) * 2.0 + 1e-12  # serpenoid period 2 s
    gait.reset()
    np.testing.assert_array_equal(gait.phase_rad, 0.0)
    assert gait.summary()["largest_phase_rad"] == [0.0] * 4
    np.testing.assert_allclose(gait.command(0.4), gait.gait.command(0.4))


def test_the_targets_of_a_shifted_gait_are_each_joint_played_early_or_late() -> None:
    gait = _phase_gait()
    gait.phase_rad[:] = [0.4, 0.1, -0.1, -0.4]
    shift, times = gait.shift_s(), np.array([0.0, 0.37, 1.9])
    expected = np.array([[gait.gait.targets(t + shift[i])[i] for i in range(8)] for t in times])
    np.testing.assert_allclose(gait.targets(times), expected)
    np.testing.assert_allclose(gait.targets(0.37), expected[1])
    np.testing.assert_allclose(gait.command(0.37), expected[1])


class _Wave(Gait):
    """A travelling wave of time; ``periodic`` False: no period; ``closed_loop``: it follows
    the measured pose (the targets depend on what the servos did)."""

    def __init__(self, *, periodic: bool, closed_loop: bool) -> None:
        self.joint_count = 8
        self.periodic, self.closed_loop = periodic, closed_loop

    @property
    def period_s(self) -> float | None:
        return 1.0 if self.periodic else None

    @property
    def uses_measured_pose(self) -> bool:
        return self.closed_loop

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        t = np.asarray(time_s, dtype=float)
        wave: FloatArray = 0.5 * np.sin(2 * np.pi * t[..., None] - 0.7 * np.arange(8))
        return wave


@pytest.mark.parametrize(("periodic", "closed_loop"), [(False, False), (True, True)])
def test_a_gait_that_cannot_be_shifted_keeps_its_phase_at_zero(
    periodic: bool, closed_loop: bool
) -> None:
    base = _Wave(periodic=periodic, closed_loop=closed_loop)
    gait = CompliantGait(base, STALL_NM, ComplianceSettings(phase_gain=100.0))
    assert not gait.shifts_phase
    for k in range(100):  # held behind the wave, as a peg would hold it
        t = k * PERIOD_S
        gait.command(t, np.zeros(8))
        slope = base.targets(t + 1e-5) - base.targets(t - 1e-5)
        gait.observe(_record(0.9 * STALL_NM * np.sign(slope), time_s=t))
    np.testing.assert_array_equal(gait.phase_rad, 0.0)
    assert gait.summary()["largest_phase_rad"] == [0.0] * 4
    assert (gait.amplitude_scale != 1.0).any()  # amplitude and offset still yield
    np.testing.assert_array_equal(gait.shift_s(), 0.0)


def test_a_periodic_gait_of_time_can_be_shifted_and_no_phase_gain_turns_it_off() -> None:
    base = _Wave(periodic=True, closed_loop=False)
    assert CompliantGait(base, STALL_NM, ComplianceSettings(phase_gain=1.0)).shifts_phase
    assert not CompliantGait(base, STALL_NM, ComplianceSettings(phase_gain=0.0)).shifts_phase


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("windows", 0),
        ("dead_band", 1.0),
        ("amplitude_gain", -1.0),
        ("return_s", 0.0),
        ("amplitude_range", (1.1, 1.5)),
        ("offset_limit_rad", float("nan")),
        ("phase_gain", -0.1),
        ("phase_gain", float("inf")),
        ("phase_limit_rad", -0.1),
        ("phase_limit_rad", 4.0),
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
