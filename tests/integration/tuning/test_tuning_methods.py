"""Each search method improves a seeded objective; the best gait replays in `snakebot run`."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path

import pytest

from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.gaits import GAITS, get_spec, load_gait_file, register_gait
from snakebot.gaits.keyframes import default_poses
from snakebot.tuning.objectives import objective_for
from snakebot.tuning.problem import EvalPlan
from snakebot.tuning.space import build_space, tuning_base
from snakebot.tuning.tuner import TuneResult, tune_gait

SHORT = EvalPlan(duration_s=2.0)


def tune(
    gait: str,
    method: str,
    budget: int,
    fixed: dict[str, object] | None = None,
    objective: str = "speed",
    heading: float = 0.0,
) -> TuneResult:
    robot = load_robot("snake8")
    space = build_space(gait, tuning_base(gait, 8, fixed or {}), joint_limit_rad=1.5)
    return tune_gait(
        robot,
        space,
        objective_for(objective, heading, robot.body_length_m),
        method,
        budget=budget,
        seed=3,
        plan=SHORT,
    )


def test_grid_beats_the_default_serpenoid_and_covers_the_box() -> None:
    result = tune("serpenoid", "grid", 9)
    assert result.grid is not None and result.grid.shape == (3, 3)
    assert result.history[0].x == (0.5, 0.1)  # bounds included
    assert result.best.feasible and result.best.value > result.baseline.value


def test_cmaes_improves_on_its_starting_point_within_the_budget() -> None:
    result = tune("serpenoid", "cmaes", 12)
    assert len(result.history) <= 12
    assert result.best.feasible and result.best.value > 1.5 * result.baseline.value


def test_cost_of_transport_is_minimised() -> None:
    result = tune("serpenoid", "cmaes", 12, objective="cost_of_transport")
    assert result.best.value < result.baseline.value


def test_ga_evolves_keyframes_from_a_weak_start() -> None:
    weak = tuple(0.15 * v for v in default_poses(8)[:16])
    result = tune("keyframes", "ga", 32, {"poses": weak, "mirror": 1})
    assert len(result.history) == 32 and result.generations[0].evaluations == 16
    assert result.best.feasible and result.best.value > 10 * result.baseline.value
    assert len(result.best.params["poses"]) == 16  # type: ignore[arg-type]


def test_tuned_gait_file_replays_to_the_same_metrics(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out, report = tmp_path / "best.toml", tmp_path / "report"
    argv = [
        "tune",
        "gait",
        "--robot",
        "snake8",
        "--method",
        "grid",
        "--budget",
        "4",
        "--duration",
        "2",
        "--objective",
        "speed_toward_heading",
        "--heading",
        "0",
        "--out",
        str(out),
        "--report",
        str(report),
        "--json",
        "--quiet",
    ]
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert {p.name for p in report.iterdir()} == {"convergence.png", "heatmap.png", "summary.json"}
    assert json.loads((report / "summary.json").read_text())["evaluations"] == 4
    name, _params, meta = load_gait_file(out)
    assert name == "serpenoid" and meta["objective"] == "speed_toward_heading"
    assert (
        main(["run", "--robot", "snake8", "--gait-file", str(out), "--duration", "2", "--json"])
        == 0
    )
    replay = json.loads(capsys.readouterr().out)
    best = summary["best"]["metrics"]
    for key in ("distance_m", "speed_mps", "cost_of_transport", "tracking_rms_rad"):
        assert replay[key] == best[key]
    assert summary["best"]["value"] == pytest.approx(replay["displacement_m"][0] / 2.0)
    assert math.isfinite(summary["wall_s"])


def test_ga_refuses_a_search_that_is_not_joint_poses(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["tune", "gait", "--gait", "serpenoid", "--method", "ga", "--budget", "2", "--quiet"]
    assert main(argv) == 2  # --method ga with a gait that has no joint poses: bad usage
    assert "the GA evolves lists of joint poses" in capsys.readouterr().err


def _pose_cycle_start(joint_count: int, fixed: Mapping[str, object]) -> dict[str, object]:
    return {"poses": default_poses(joint_count)[: 2 * joint_count], "mirror": 1.0, **fixed}


def test_ga_evolves_any_gait_that_declares_a_list_of_joint_poses() -> None:
    keyframes = get_spec("keyframes")
    poses = replace(keyframes.param("poses"), bounds=(-0.5, 0.5))
    spec = replace(
        keyframes,
        name="pose_cycle",
        params=(poses, *keyframes.params[1:]),
        tuning_start=_pose_cycle_start,
    )
    register_gait(spec)
    try:
        result = tune("pose_cycle", "ga", 6)
    finally:
        GAITS.unregister("pose_cycle")
    assert result.space.names[0] == "poses[0]" and len(result.space.dims) == 16
    assert result.space.upper.max() == 0.5
    assert len(result.history) == 6 and result.generations[0].evaluations == 6
