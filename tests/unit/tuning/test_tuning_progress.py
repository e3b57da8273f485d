"""The progress line: candidates per second always, live workers and re-runs on the Ray executor."""

from __future__ import annotations

import io
from dataclasses import dataclass

from snakebot.tuning.objectives import objective_for
from snakebot.tuning.progress import ProgressBar, gait_summary_text


@dataclass
class _Problem:
    evaluations: int
    live_workers: int | None = None
    rescored: int = 0
    best: None = None
    objective: object = objective_for("speed", 0.0, 1.0)


def _line(problem: _Problem) -> str:
    out = io.StringIO()
    bar = ProgressBar(budget=10, stream=out, every_s=0.0)
    bar.start -= 2.0  # two seconds in
    bar(problem)  # type: ignore[arg-type]
    return out.getvalue()


def test_the_line_shows_candidates_per_second() -> None:
    line = _line(_Problem(evaluations=4))
    assert "4/10 evals" in line
    assert "2.0 cand/s" in line
    assert "workers live" not in line


def test_on_ray_it_shows_live_workers_and_re_runs() -> None:
    assert "2 workers live" in _line(_Problem(evaluations=4, live_workers=2))
    line = _line(_Problem(evaluations=6, live_workers=1, rescored=3))
    assert "1 worker live (3 re-run after a lost worker)" in line


def test_the_summary_says_where_it_ran() -> None:
    summary = {
        "robot": "snake8",
        "gait": "serpenoid",
        "method": "cmaes",
        "objective": "speed",
        "objective_unit": "m/s",
        "best": {"value": 0.4, "params": {"omega": 1.0}},
        "baseline": {"value": 0.1, "params": {}},
        "searched": [{"name": "omega"}],
        "evaluations": 12,
        "feasible_evaluations": 10,
        "wall_s": 3.0,
        "workers": 2,
    }
    assert "on 2 workers" in gait_summary_text({**summary, "executor": "local"})
    ray = {**summary, "executor": "ray", "address": "10.0.0.5:6379"}
    assert "on the Ray cluster at 10.0.0.5:6379" in gait_summary_text(ray)
    assert gait_summary_text({**ray, "address": None}).endswith("in 3.0 s on Ray")
