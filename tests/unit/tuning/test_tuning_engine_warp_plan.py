"""The warp engine refuses the plans it cannot run, naming the field, before it builds anything
(no twin, no Ray): it needs neither the gpu extra nor a device to say so."""

from __future__ import annotations

import pytest

from snakebot.config import load_robot
from snakebot.errors import ConfigError
from snakebot.tuning.engine_warp import WarpGaitProblem
from snakebot.tuning.objectives import objective_for
from snakebot.tuning.problem import EvalPlan
from snakebot.tuning.space import build_space, tuning_base


@pytest.mark.parametrize(
    ("plan", "field"),
    [
        (EvalPlan(engine="warp", friction_model="scale"), "friction_model"),
        (EvalPlan(engine="warp", executor="ray"), "executor"),
    ],
)
def test_a_plan_the_warp_engine_cannot_run_is_refused_first(
    plan: EvalPlan, field: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    def built(*args: object, **kwargs: object) -> None:
        raise AssertionError("the twin was built for a refused plan")

    monkeypatch.setattr("snakebot.tuning.problem.TwinBatch", built)
    robot = load_robot("snake8")
    space = build_space("serpenoid", tuning_base("serpenoid", 8, {}), None, {}, 1.0)
    objective = objective_for("speed", 0.0, robot.body_length_m)
    with pytest.raises(ConfigError) as caught:
        WarpGaitProblem(robot, space, objective, plan)
    assert caught.value.source == field
