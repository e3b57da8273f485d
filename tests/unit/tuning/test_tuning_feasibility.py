from __future__ import annotations

import math

import numpy as np
import pytest

from snakebot.tuning.feasibility import Envelope, assess
from snakebot.tuning.responses import chirp_commands, step_commands, step_metrics
from snakebot.tuning.trace import Trace

N, K, DT = 2, 100, 0.01


def envelope() -> Envelope:
    return Envelope(
        lower_rad=np.full(N, -1.0),
        upper_rad=np.full(N, 1.0),
        max_speed_rad_s=5.0,
        no_load_speed_rad_s=6.0,
        torque_limit_nm=1.0,
        rest_com_z_m=0.02,
        lift_limit_m=0.04,
    )


def trace(**changes: np.ndarray) -> Trace:
    t = np.arange(1, K + 1) * DT
    wave = 0.5 * np.sin(np.outer(t, [1.0, 1.0]))
    fields = {
        "time_s": t,
        "target_rad": wave,
        "command_rad": wave,
        "position_rad": wave,
        "velocity_rad_s": np.zeros((K, N)),
        "effort_nm": np.zeros((K, N)),
        "actuator_force_nm": np.zeros((K, N)),
        "positive_work_j": np.zeros((K, N)),
        "com_m": np.tile([0.0, 0.0, 0.02], (K, 1)),
        "head_quat": np.tile([1.0, 0.0, 0.0, 0.0], (K, 1)),
        "clearance_m": np.zeros(K),
    }
    fields.update(changes)
    return Trace(
        dt_s=DT, start_com_m=np.zeros(3), start_head_quat=np.array([1.0, 0, 0, 0]), **fields
    )  # type: ignore[arg-type]


def test_a_calm_run_is_feasible() -> None:
    violations = assess(trace(), envelope(), K * DT)
    assert violations.feasible and violations.total == 0.0


def test_each_way_out_of_the_envelope_is_measured() -> None:
    env = envelope()
    beyond = np.full((K, N), 1.25)
    assert assess(trace(target_rad=beyond), env, K * DT).joint_limit_rad == pytest.approx(0.25)
    fast = np.outer(np.arange(K) * 0.06, [1.0, 0.0])  # 6 rad/s requested vs 5 allowed
    assert assess(trace(target_rad=fast), env, K * DT).speed_excess == pytest.approx(0.2)
    force = np.zeros((K, N))
    force[10:50, 1] = 0.99  # 0.4 s at the limit, 0.25 s allowed
    result = assess(trace(actuator_force_nm=force), env, K * DT)
    assert result.saturation_excess_s == pytest.approx(0.15)
    lifted = np.zeros(K)
    lifted[:25] = 0.01  # no module within 2 mm of the floor for a quarter of the run
    assert assess(trace(clearance_m=lifted), env, K * DT).airborne_fraction == 0.25


def test_a_run_cut_short_counts_the_rest_as_airborne() -> None:
    full = trace()
    arrays = {
        k: v[:40]
        for k, v in full.__dict__.items()
        if k not in ("dt_s", "start_com_m", "start_head_quat", "stop_reason")
    }
    cut = Trace(**{**full.__dict__, **arrays, "stop_reason": "airborne"})
    result = assess(cut, envelope(), K * DT)
    assert result.airborne_fraction == pytest.approx(0.6) and not result.feasible


def test_flipped_needs_the_head_upside_down_unless_rolling_is_allowed() -> None:
    env = envelope()
    assert env.flipped(np.array([-0.9, 0.2])).tolist() == [True, False]
    rolling = Envelope(**{**env.__dict__, "allow_roll": True})
    assert not rolling.flipped(np.array([-1.0])).any()


def test_step_metrics_of_a_second_order_response() -> None:
    t = np.arange(1, 301) * DT
    zeta, wn = 0.4, 20.0
    wd = wn * math.sqrt(1 - zeta**2)
    after = np.clip(t - 0.5, 0.0, None)
    y = 1 - np.exp(-zeta * wn * after) * (
        np.cos(wd * after) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * after)
    )
    metrics = step_metrics(t, 0.1 + 0.2 * y, 0.1, 0.3, 0.5)
    expected = math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2))
    assert metrics.overshoot == pytest.approx(expected, abs=0.01)
    assert 0.05 < metrics.rise_time_s < 0.12
    assert 0.2 < metrics.settling_time_s < 0.5
    assert metrics.steady_state_error_rad == pytest.approx(0.0, abs=1e-4)


def test_a_step_stopped_short_by_friction_settles_with_an_error() -> None:
    t = np.arange(1, 101) * DT
    y = np.where(t < 0.3, 0.0, 0.15)  # stuck at 75 % of a 0.2 rad step
    metrics = step_metrics(t, y, 0.0, 0.2, 0.3)
    assert math.isnan(metrics.rise_time_s)
    assert metrics.settling_time_s == 0.0 or metrics.settling_time_s < 0.05
    assert metrics.steady_state_error_rad == pytest.approx(0.05)


def test_test_signals_move_one_joint_and_stay_within_limits() -> None:
    hold = np.array([0.0, 1.4])
    lower, upper = np.full(2, -1.5), np.full(2, 1.5)
    step = step_commands(hold, 1, 0.2, lower, upper, rate_hz=100, lead_s=0.1, step_s=0.2)
    assert step.shape == (30, 2) and step[-1].tolist() == pytest.approx([0.0, 1.2])
    chirp = chirp_commands(hold, 0, 0.1, rate_hz=100, duration_s=2.0)
    assert np.all(chirp[:, 1] == 1.4) and np.abs(chirp[:, 0]).max() <= 0.1


def rolling_quats(upside_down_fraction: float, stretch: int = 20) -> np.ndarray:
    """Head quaternions (K, 4): upside down (rolled pi about x) in stretches of ``stretch``
    cycles, short of the early stop's 0.25 s, for ``upside_down_fraction`` of the run."""
    quats = np.tile([1.0, 0.0, 0.0, 0.0], (K, 1))
    down = 0
    for start in range(0, K, 2 * stretch):
        take = min(stretch, round(upside_down_fraction * K) - down)
        if take <= 0:
            break
        quats[start : start + take] = [0.0, 1.0, 0.0, 0.0]
        down += take
    return quats


def test_a_gait_upside_down_43_percent_of_the_time_is_infeasible_unless_it_may_roll() -> None:
    # The audit: the tuner's "flipped" check (0.25 s upside down without a break) missed a gait
    # that rolled over and back, upside down 43 % of the time.
    env = envelope()
    rolled = trace(head_quat=rolling_quats(0.43))
    assert np.mean(rolled.up_z < -0.5) == pytest.approx(0.43)
    result = assess(rolled, env, K * DT)
    assert result.upside_down_fraction == pytest.approx(0.43)
    assert not result.feasible
    assert assess(rolled, Envelope(**{**env.__dict__, "allow_roll": True}), K * DT).feasible
    assert assess(trace(head_quat=rolling_quats(0.05)), env, K * DT).feasible


def test_sinking_into_the_floor_or_chattering_is_infeasible() -> None:
    env = Envelope(**{**envelope().__dict__, "radius_m": 0.02})
    sunk = np.zeros(K)
    sunk[30:40] = -0.008  # 8 mm into the floor: 40 % of the radius, 25 % allowed
    result = assess(trace(clearance_m=sunk), env, K * DT)
    assert result.penetration_excess == pytest.approx(0.15)
    assert not result.feasible
    chatter = np.tile([[1.0, 0.0], [-1.0, 0.0]], (K // 2, 1))  # joint 0 reverses every cycle
    result = assess(trace(velocity_rad_s=chatter), env, K * DT)
    assert result.chatter_excess == pytest.approx(0.99 - 0.25)
    assert not result.feasible
