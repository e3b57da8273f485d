"""`rl compare --executor ray` as a user runs it: Ray Tune trials on Ray started here (the laptop
case) and on the session's two-node loopback cluster; the same table, curves and actors as a
local run, ASHA stopping a hopeless trial, --resume after Ctrl-C, and a lost node's trial run
again.

Tiny trainings (256 steps a trial, 128-step rollouts, 4 s episodes at 25 Hz); PPO on one CPU is
deterministic for a seed on a machine, so the Ray run must match the local one bit for bit.
"""

from __future__ import annotations

import csv
import json
import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

pytest.importorskip("ray.tune", reason="the 'cluster' extra (ray[tune]) is not installed")

from snakebot.testing.cluster import LoopbackCluster, node_environment

pytestmark = [pytest.mark.slow, pytest.mark.cluster]
FAST = ["--set", "action_hz=25", "--set", "control_hz=25", "--set", "episode_s=4"]
TINY = ["--steps", "256", "--rollout", "128", "--n-envs", "1", "--vec", "dummy", *FAST]
SWEEP = ["rl", "compare", "--encodings", "sinusoid,dft", "--seeds", "2", *TINY]
TRIALS = ("sinusoid/seed-0", "sinusoid/seed-1", "dft/seed-0", "dft/seed-1")
RAY = ["--executor", "ray", "--ray-cpus", "1"]  # Ray started here, one trial at a time


def cli(
    *args: str, timeout: float = 600, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "snakebot", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
    )


def on(cluster: LoopbackCluster) -> list[str]:
    """The options of a sweep on the session's two-node loopback cluster (no Ray to start)."""
    return ["--executor", "ray", "--address", cluster.address]


def curve(folder: Path) -> list[dict[str, str]]:
    """The learning curve without its clock columns (wall time, throughput)."""
    with (folder / "learning_curve.csv").open() as f:
        rows = list(csv.DictReader(f))
    return [{k: v for k, v in r.items() if k not in ("wall_s", "steps_per_s")} for r in rows]


def stream(
    argv: list[str], env: dict[str, str] | None = None
) -> tuple[queue.Queue[str], subprocess.Popen[str]]:
    """``snakebot ARGV`` started, its stderr lines arriving in the queue as it prints them."""
    process = subprocess.Popen(
        [sys.executable, "-m", "snakebot", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    lines: queue.Queue[str] = queue.Queue()
    stderr = process.stderr
    assert stderr is not None

    def read() -> None:
        for line in stderr:
            lines.put(line)

    threading.Thread(target=read, daemon=True).start()
    return lines, process


def wait_for(
    lines: queue.Queue[str], process: subprocess.Popen[str], text: str, timeout_s: float = 400
) -> list[str]:
    """The lines up to the first that holds ``text``; fails when the process ends first."""
    seen: list[str] = []
    deadline = time.monotonic() + timeout_s
    while not seen or text not in seen[-1]:
        assert time.monotonic() < deadline and process.poll() is None, "".join(seen)
        try:
            seen.append(lines.get(timeout=1))
        except queue.Empty:
            continue
    return seen


def drain(lines: queue.Queue[str]) -> list[str]:
    time.sleep(0.5)  # the reader's last lines
    out = []
    while not lines.empty():
        out.append(lines.get())
    return out


@pytest.fixture(scope="module")
def local(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    out = tmp_path_factory.mktemp("local") / "compare"
    done = cli(*SWEEP, "--out", str(out))
    assert done.returncode == 0, done.stderr
    return out, done.stdout


def assert_same_as_local(local: tuple[Path, str], out: Path, stdout: str) -> None:
    local_out, local_stdout = local
    table = local_stdout.splitlines()[:3]
    assert stdout.splitlines()[:3] == table  # the printed table, header and both encodings
    mine, theirs = (json.loads((o / "compare.json").read_text()) for o in (out, local_out))
    assert mine["table"] == theirs["table"]
    assert list(mine["runs"]) == list(TRIALS)
    for name in TRIALS:
        assert curve(out / name) == curve(local_out / name), name
        actor = (out / name / "actor.npz").read_bytes()
        assert actor == (local_out / name / "actor.npz").read_bytes(), name
        assert mine["runs"][name]["folder"] == str(out / name)
        assert json.loads((out / name / "policy.json").read_text())["steps"] == 256


def test_a_ray_sweep_gives_the_local_table_and_policy_folders(
    local: tuple[Path, str], tmp_path: Path
) -> None:
    out = tmp_path / "compare"
    done = cli(*SWEEP, *RAY, "--out", str(out))
    assert done.returncode == 0, done.stderr
    assert_same_as_local(local, out, done.stdout)
    assert "sinusoid/seed-1:       128/256 steps" in done.stderr  # its progress, per rollout
    assert (out / "compare.png").stat().st_size > 10_000
    # The experiment stays for --resume, and a second run refuses to replace it
    again = cli(*SWEEP, *RAY, "--out", str(out), "--dry-run")
    assert again.returncode == 1 and "ray-tune" in again.stderr


def test_asha_stops_a_clearly_hopeless_trial_at_its_first_rung(
    loopback_cluster: LoopbackCluster, tmp_path: Path
) -> None:
    # A step cost of 5 per step makes every episode's return about -500 against the about -5
    # of the ordinary task's: at the first rung (128 steps) it is in the worse half, stopped.
    out = tmp_path / "asha"
    done = cli(
        "rl",
        "compare",
        "--encodings",
        "sinusoid",
        "--grid",
        "step_cost=0.01,5",
        *TINY[:1],
        "512",
        *TINY[2:],
        *on(loopback_cluster),
        "--scheduler",
        "asha",
        "--max-concurrent-trials",
        "1",
        "--out",
        str(out),
        "--json",
        env=node_environment(),
    )
    assert done.returncode == 0, done.stderr
    runs = json.loads(done.stdout)["runs"]
    good, hopeless = runs["sinusoid/step_cost=0.01"], runs["sinusoid/step_cost=5"]
    assert not good["stopped_early"] and good["steps"] == 512
    assert hopeless["stopped_early"] and hopeless["steps"] == 128
    assert hopeless["final_mean_return"] < 10 * good["final_mean_return"] < 0
    assert [r["steps"] for r in curve(out / "sinusoid/step_cost=5")] == ["128"]
    assert not (out / "sinusoid/step_cost=5/policy.zip").exists()  # it never got to the end
    assert (out / "sinusoid/step_cost=0.01/policy.zip").exists()
    assert "sinusoid/step_cost=5: stopped early" in done.stderr


def test_an_interrupted_sweep_resumes_keeping_its_finished_trials(
    local: tuple[Path, str], loopback_cluster: LoopbackCluster, tmp_path: Path
) -> None:
    out = tmp_path / "compare"
    ray = on(loopback_cluster)
    lines, sweep = stream([*SWEEP, *ray, "--out", str(out)], env=node_environment())
    seen = []
    try:
        seen += wait_for(lines, sweep, "  sinusoid/seed-0: done")
        sweep.send_signal(signal.SIGINT)  # Ctrl-C: Tune saves the experiment and ends
        sweep.wait(timeout=300)
    finally:
        if sweep.poll() is None:
            sweep.kill()
            sweep.wait()
    seen += drain(lines)
    assert sweep.returncode == 130, "".join(seen)
    assert "--resume" in "".join(seen)
    assert not (out / "compare.json").exists()

    resumed = cli(*SWEEP, *ray, "--out", str(out), "--resume", env=node_environment())
    assert resumed.returncode == 0, resumed.stderr
    assert "sinusoid/seed-0" not in resumed.stderr  # finished before Ctrl-C: not trained again
    assert "dft/seed-1: done" in resumed.stderr
    assert_same_as_local(local, out, resumed.stdout)
    other = cli(*SWEEP, "--steps", "512", *ray, "--out", str(out), "--resume")
    assert other.returncode == 2 and "other" in other.stderr


def test_a_sweep_across_two_loopback_nodes_survives_losing_one(
    loopback_cluster: LoopbackCluster, tmp_path: Path
) -> None:
    # Two trials at once, one on each one-CPU node; the second node dies while they train: its
    # trial fails, runs again from the start on the head, and the table is the local run's.
    sweep = ["rl", "compare", "--encodings", "sinusoid", "--seeds", "2", *TINY]
    sweep[sweep.index("--steps") + 1] = "1024"  # eight rollouts: the kill lands mid-trial
    local = cli(*sweep, "--out", str(tmp_path / "local"))
    assert local.returncode == 0, local.stderr
    out = tmp_path / "cluster"
    argv = [*sweep, *on(loopback_cluster), "--out", str(out)]
    lines, process = stream(argv, env=node_environment())
    seen = []
    try:
        seen += wait_for(lines, process, "128/1024 steps")  # both nodes are training now
        loopback_cluster.kill_node(1)
        process.wait(timeout=400)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        loopback_cluster.restore()
    seen += drain(lines)
    stderr = "".join(seen)
    assert process.returncode == 0, stderr
    assert ": failed, running it again from the start" in stderr  # the lost node's trial
    assert process.stdout is not None
    assert process.stdout.read().splitlines()[:2] == local.stdout.splitlines()[:2]
    for name in ("sinusoid/seed-0", "sinusoid/seed-1"):
        assert curve(out / name) == curve(tmp_path / "local" / name), name
        assert (out / name / "actor.npz").read_bytes() == (
            tmp_path / "local" / name / "actor.npz"
        ).read_bytes()
