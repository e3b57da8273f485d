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
    header, trained, zero, *_ = out.getvalue().splitlines()
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
    header, zero, small, *_ = out.getvalue().splitlines()
    cot = slice(header.index("CoT") - 4, header.index("CoT") + 3)
    assert zero[cot].strip() == "n/a"
    assert small[cot].strip() == "0.00408"  # 0.2 / (1 kg * 9.81 * 5 m), not 0.00


def test_every_row_gets_a_95_percent_interval_over_its_episodes() -> None:
    # 14 of 20 goals reached: the bootstrap's interval of the success rate holds 70 % and is
    # about as wide as the binomial's (+-20 points); all-successes collapses to the point.
    mixed = EvalResult("policy", 1.0, [_episode(i, i < 14) for i in range(20)])
    always = EvalResult("bearing", 1.0, [_episode(i, True) for i in range(20)])
    low, high = mixed.summary()["interval95"]["success_rate"]
    assert 0.4 < low < 0.6 and 0.8 < high < 0.95
    assert always.summary()["interval95"]["success_rate"] == (1.0, 1.0)
    assert always.summary()["interval95"]["time_to_goal_s"] == (6.0, 6.0)
    assert mixed.summary() == mixed.summary()  # a fixed generator: the same table every run
    out = io.StringIO()
    print_table({"policy": mixed, "bearing": always}, out)
    lines = out.getvalue().splitlines()
    assert lines[3].startswith("95% intervals (bootstrap over episodes")
    policy_row = next(line for line in lines[5:] if line.startswith("policy"))
    assert "[100, 100]" in lines[-1] and "[6.0, 6.0]" in lines[-1]
    assert "[" in policy_row and "n/a" not in policy_row.split("]")[0]


def test_training_seeds_make_one_row_with_a_t_interval_over_them() -> None:
    # Three training seeds reaching 10, 14 and 18 of 20 goals: the row shows their mean (70 %)
    # and Student's t interval, mean +- 4.303 x sd / sqrt(3) = 70 +- 49.7 points.
    from pathlib import Path

    from snakebot.rl.evaluate import SeedsResult

    runs = [
        EvalResult("policy", 1.0, [_episode(i, i < reached) for i in range(20)])
        for reached in (10, 14, 18)
    ]
    summary = SeedsResult("policy", [Path(f"seed-{s}") for s in range(3)], runs).summary()
    assert summary["training_seeds"] == 3 and summary["interval_over"] == "training seeds"
    assert abs(summary["success_rate"] - 0.7) < 1e-12
    low, high = summary["interval95"]["success_rate"]
    assert abs((high - low) / 2 - 4.3027 * 0.2 / 3**0.5) < 1e-3
    assert [p["folder"] for p in summary["policies"]] == ["seed-0", "seed-1", "seed-2"]
    assert summary["policies"][1]["successes"] == 14
    out = io.StringIO()
    print_table({"policy": SeedsResult("policy", [Path("a"), Path("b"), Path("c")], runs)}, out)
    assert "95% intervals (the policy over 3 training seeds, the rest bootstrap" in out.getvalue()
