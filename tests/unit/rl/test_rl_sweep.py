"""The trials of ``rl compare`` (encodings x seeds x grid), their folders and the table."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from snakebot.cli.main import main
from snakebot.errors import ConfigError
from snakebot.rl.settings import GOAL_ENV_ID, GoalSettings, settings_dict, split_kwargs
from snakebot.rl.sweep import SweepPlan, TrialOutcome, comparison_rows, comparison_table
from snakebot.rl.train import CurvePoint, TrainResult


def kwargs(encoding: str) -> dict[str, object]:
    return settings_dict(*split_kwargs({"encoding": encoding}, GoalSettings))


def plan(**options: object) -> SweepPlan:
    runs = {"sinusoid": kwargs("sinusoid"), "dft": kwargs("dft")}
    return SweepPlan(GOAL_ENV_ID, runs, 512, rollout_steps=256, **options)  # type: ignore[arg-type]


def test_one_seed_and_no_grid_train_where_rl_compare_always_did() -> None:
    assert [t.name for t in plan().trials()] == ["sinusoid", "dft"]


def test_seeds_and_grid_points_each_get_a_folder_in_order() -> None:
    trials = plan(seeds=(3, 4), grid={"learning_rate": (3e-4, 1e-4), "step_cost": (0.02,)})
    assert [t.name for t in trials.trials()][:4] == [
        "sinusoid/learning_rate=0.0003,step_cost=0.02/seed-3",
        "sinusoid/learning_rate=0.0003,step_cost=0.02/seed-4",
        "sinusoid/learning_rate=0.0001,step_cost=0.02/seed-3",
        "sinusoid/learning_rate=0.0001,step_cost=0.02/seed-4",
    ]
    assert len(trials.trials()) == 8
    trial = trials.trials()[2]
    settings = trials.settings(trial)
    assert settings.seed == 3 and settings.ppo == {"learning_rate": 1e-4}
    assert settings.env_kwargs["step_cost"] == 0.02
    assert settings.env_kwargs["encoding"] == "sinusoid"
    assert settings.rollout_steps == 256


@pytest.mark.parametrize(
    ("grid", "named"),
    [
        ({"goal_radius": (1, 2)}, "goal_radius_bl"),  # unknown: the valid keys are listed
        ({"learning_rate": (2.0,)}, "learning_rate"),  # a PPO value out of range
        ({"goal_radius_bl": (-1.0,)}, "goal_radius_bl"),  # an env value its settings refuse
        ({"encoding": ("dft",)}, "encoding"),
        ({"gamma": (0.9, 0.9)}, "distinct"),
    ],
)
def test_a_bad_grid_is_refused_before_anything_trains(
    grid: dict[str, tuple[object, ...]], named: str
) -> None:
    with pytest.raises(ConfigError, match=named) as caught:
        plan(grid=grid)
    assert caught.value.source == "grid"


def outcome(name: str, seed: int, returns: list[float], stopped: bool = False) -> TrialOutcome:
    trial = next(t for t in plan(seeds=(0, 1)).trials() if t.name == name)
    assert trial.seed == seed
    curve = [CurvePoint(256 * (i + 1), 1.0, 1, r, 0.5, 100.0, 10.0) for i, r in enumerate(returns)]
    return TrialOutcome(trial, TrainResult(curve, 2.0, 256 * len(returns), Path(name)), stopped)


def test_the_table_has_the_mean_and_spread_over_seeds_and_counts_early_stops() -> None:
    rows = comparison_rows(
        [
            outcome("sinusoid/seed-0", 0, [-5.0, 1.0]),
            outcome("sinusoid/seed-1", 1, [-3.0, 3.0]),
            outcome("dft/seed-0", 0, [math.nan], stopped=True),
            outcome("dft/seed-1", 1, [math.nan, math.nan]),
        ]
    )
    assert rows[0]["final_mean_return"] == 2.0 and rows[0]["final_mean_return_sd"] == 1.0
    assert rows[0]["steps"] == 512 and rows[0]["seeds"] == [0, 1]
    assert rows[1]["final_mean_return"] is None and rows[1]["stopped_early"] == 1
    text = comparison_table(rows).splitlines()
    header = ["encoding", "grid", "seeds", "stopped", "steps", "return", "±", "sd", "success"]
    assert text[0].split() == header
    assert text[1].split() == ["sinusoid", "-", "2", "0", "512", "2.00", "1.00", "50%"]
    assert text[2].split() == ["dft", "-", "2", "1", "384", "n/a", "n/a", "50%"]


def test_ray_options_are_usage_errors_on_a_local_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["rl", "compare", "--out", str(tmp_path / "c"), "--dry-run"]
    assert main([*argv, "--scheduler", "asha"]) == 2
    assert "--scheduler: needs --executor ray" in capsys.readouterr().err
    assert main([*argv, "--resume"]) == 2
    assert main([*argv, "--grid", "gamma"]) == 2  # a flag's value: KEY=V1,...
    assert "--grid" in capsys.readouterr().err
    ray = [*argv, "--executor", "ray", "--address", "127.0.0.1:6390"]
    assert main([*ray, "--ray-cpus", "2"]) == 2  # sizes only the Ray started here
    assert "--ray-cpus" in capsys.readouterr().err
    assert main([*ray, "--asha-grace", "512"]) == 2
    assert "--asha-grace: sets the asha scheduler's first rung" in capsys.readouterr().err


def test_a_dry_run_lists_every_trial(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["rl", "compare", "--encodings", "dft", "--seeds", "2", "--grid", "gamma=0.9,0.99"]
    assert main([*argv, "--out", str(tmp_path / "c"), "--dry-run", "--json"]) == 0
    out = capsys.readouterr().out
    for name in ("dft/gamma=0.9/seed-0", "dft/gamma=0.99/seed-1"):
        assert name in out
    assert not (tmp_path / "c").exists()
