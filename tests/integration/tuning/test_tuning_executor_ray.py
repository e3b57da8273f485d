"""Gait search on the Ray executor: the same search as the local one, across two real loopback
nodes, also when the second node dies mid-search; and `tune gait --executor ray` on the CLI."""

from __future__ import annotations

import json
import os
import threading
from dataclasses import replace

import pytest

pytest.importorskip("ray", reason="the cluster tests need Ray: pip install 'snakebot[cluster]'")

from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.errors import ConfigError
from snakebot.gaits.keyframes import default_poses
from snakebot.testing.cluster import LoopbackCluster
from snakebot.tuning.objectives import objective_for
from snakebot.tuning.problem import EvalPlan, Listener, SearchProblem
from snakebot.tuning.space import build_space, tuning_base
from snakebot.tuning.tuner import TuneResult, evaluation_dict, tune_gait

pytestmark = pytest.mark.cluster

PLAN = EvalPlan(duration_s=2.0)


def search(
    method: str, budget: int, plan: EvalPlan, listener: Listener | None = None
) -> TuneResult:
    """snake8: serpenoid's omega x phase_lag, or for the GA its keyframe poses (mirrored)."""
    robot = load_robot("snake8")
    gait, fixed = "serpenoid", {}
    if method == "ga":
        gait, fixed = "keyframes", {"poses": tuple(0.15 * v for v in default_poses(8)[:16])}
        fixed["mirror"] = 1
    space = build_space(gait, tuning_base(gait, 8, fixed), joint_limit_rad=1.5)
    objective = objective_for("speed", 0.0, robot.body_length_m)
    return tune_gait(
        robot, space, objective, method, budget=budget, seed=7, plan=plan, listener=listener
    )


def same_search(a: TuneResult, b: TuneResult) -> None:
    assert [evaluation_dict(e) for e in a.history] == [evaluation_dict(e) for e in b.history]
    assert [e.x for e in a.history] == [e.x for e in b.history]
    assert evaluation_dict(a.best) == evaluation_dict(b.best)
    assert evaluation_dict(a.baseline) == evaluation_dict(b.baseline)


@pytest.mark.parametrize(("method", "budget"), [("cmaes", 12), ("grid", 9), ("ga", 32)])
def test_ray_searches_like_local(
    loopback_cluster: LoopbackCluster, method: str, budget: int
) -> None:
    live: list[int | None] = []

    def watch(problem: SearchProblem) -> None:
        live.append(getattr(problem, "live_workers", None))

    local = search(method, budget, PLAN)
    remote = search(
        method, budget, replace(PLAN, executor="ray", address=loopback_cluster.address), watch
    )
    same_search(local, remote)
    assert len(local.history) == budget
    assert live and all(n == 2 for n in live), "both nodes scored every generation"
    assert remote.summary()["executor"] == "ray"
    assert loopback_cluster.foreign_sockets(extra_pids=(os.getpid(),)) == []


def test_a_node_lost_mid_search_costs_only_its_candidates(
    loopback_cluster: LoopbackCluster,
) -> None:
    seen: list[tuple[int | None, int]] = []
    killer: list[threading.Timer] = []

    def kill_during_the_next_generation(problem: SearchProblem) -> None:
        seen.append((getattr(problem, "live_workers", None), getattr(problem, "rescored", 0)))
        if not killer:
            killer.append(threading.Timer(0.3, loopback_cluster.kill_node, args=(1,)))
            killer[0].start()

    local = search("cmaes", 18, PLAN)
    try:
        remote = search(
            "cmaes",
            18,
            replace(PLAN, executor="ray", address=loopback_cluster.address),
            kill_during_the_next_generation,
        )
        killer[0].join()
        assert len(loopback_cluster.killed) == 1 and len(loopback_cluster.nodes) == 1
    finally:
        loopback_cluster.restore()
    same_search(local, remote)
    assert seen[0] == (2, 0)
    live, rescored = seen[-1]
    assert live == 1, "the lost node's worker is gone"
    assert 0 < rescored < 6, "only the lost share was scored again"


def test_tune_gait_executor_ray_on_the_command_line(
    loopback_cluster: LoopbackCluster, capsys: pytest.CaptureFixture[str]
) -> None:
    common = ["tune", "gait", "--robot", "snake8", "--method", "cmaes", "--budget", "12"]
    common += ["--duration", "2", "--seed", "3", "--json", "--quiet"]
    assert main([*common, "--executor", "local"]) == 0
    local = json.loads(capsys.readouterr().out)
    assert main([*common, "--executor", "ray", "--address", loopback_cluster.address]) == 0
    remote = json.loads(capsys.readouterr().out)
    assert (remote["executor"], remote["address"]) == ("ray", loopback_cluster.address)
    assert remote["best"] == local["best"]
    assert remote["baseline"] == local["baseline"]
    assert remote["evaluations"] == local["evaluations"] == 12


def test_an_error_on_a_worker_comes_back_as_itself(loopback_cluster: LoopbackCluster) -> None:
    # 333 Hz is no whole number of 2 ms physics steps: the engine refuses it when it runs.
    bad = replace(PLAN, rate_hz=333.0)
    with pytest.raises(ConfigError, match="rate") as local:
        search("cmaes", 12, bad)
    remote = replace(bad, executor="ray", address=loopback_cluster.address)
    with pytest.raises(ConfigError) as caught:
        search("cmaes", 12, remote)
    assert str(local.value) in str(caught.value)
