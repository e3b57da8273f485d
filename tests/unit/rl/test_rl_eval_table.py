"""`rl eval`'s table: a line per policy, columns that line up, n/a where a mean has no episodes."""

from __future__ import annotations

import io

from snakebot.rl.evaluate import EpisodeStats, EvalResult, print_table


def _episode(seed: int, success: bool) -> EpisodeStats:
    return EpisodeStats(
        seed,
        episode_return=3.0 if success else -1.0,
        steps=60,
        success=success,
        duration_s=6.0,
        path_m=1.8,
        positive_work_j=2.0,
    )


def test_a_policy_that_reached_no_goal_shows_n_a_in_the_time_to_goal_column() -> None:
    results = {
        "policy": EvalResult("policy", 1.0, [_episode(0, True), _episode(1, True)]),
        "zero": EvalResult("zero", 1.0, [_episode(0, False), _episode(1, False)]),
    }
    out = io.StringIO()
    print_table(results, out)
    header, trained, zero = out.getvalue().splitlines()
    assert "100%" in trained and "6.0 s" in trained
    assert "  0%" in zero and "n/a" in zero and "n/a s" not in zero
    # every column ends where its header ends
    assert len(trained) == len(zero) == len(header)
    assert trained.index(" 0.300 m/s") == zero.index(" 0.300 m/s")


def test_a_velocity_policy_has_no_success_rate_to_show() -> None:
    episode = EpisodeStats(
        0,
        100.0,
        300,
        success=False,
        duration_s=30.0,
        path_m=6.0,
        positive_work_j=9.0,
        speed_error_mps=0.05,
        command=(0.2, 0.0),
        achieved=(0.18, 0.01),
    )
    summary = EvalResult("policy", 1.0, [episode]).summary()
    assert summary["success_rate"] is None and summary["speed_error_mps"] == 0.05
    out = io.StringIO()
    print_table({"policy": EvalResult("policy", 1.0, [episode])}, out)
    assert "0%" not in out.getvalue() and "mean |speed - command| 0.050 m/s" in out.getvalue()


def test_a_policy_that_stayed_put_has_no_cost_of_transport_and_a_small_one_is_not_zero() -> None:
    # Measured: a zero policy's COM drifted microns and its CoT printed as 0.00 (1.6e-21).
    still = EpisodeStats(
        0, -12.0, 300, success=False, duration_s=30.0, path_m=2e-6, positive_work_j=3e-20
    )
    frugal = EpisodeStats(
        0, 1.0, 300, success=False, duration_s=30.0, path_m=5.0, positive_work_j=0.2
    )
    results = {
        "zero": EvalResult("zero", 1.0, [still, still]),
        "frugal": EvalResult("frugal", 1.0, [frugal]),
    }
    assert results["zero"].summary()["cost_of_transport"] is None
    out = io.StringIO()
    print_table(results, out)
    header, zero, small = out.getvalue().splitlines()
    cot = slice(header.index("CoT") - 4, header.index("CoT") + 3)
    assert zero[cot].strip() == "n/a"
    assert small[cot].strip() == "0.00408"  # 0.2 / (1 kg * 9.81 * 5 m), not 0.00
