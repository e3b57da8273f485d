"""A real two-node Ray cluster on 127.0.0.1: both nodes work, nothing leaves loopback, a killed
node is noticed, and stopping leaves no process behind."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ray = pytest.importorskip(
    "ray", reason="the cluster tests need Ray: pip install 'snakebot[cluster]'"
)

from snakebot.cluster import ray_session, wait_for_nodes  # noqa: E402
from snakebot.testing.cluster import LoopbackCluster, node_environment  # noqa: E402

pytestmark = pytest.mark.cluster


@ray.remote(num_cpus=1)
class _Where:
    def node(self) -> str:
        return str(ray.get_runtime_context().get_node_id())


def test_both_nodes_run_work_over_loopback_only(loopback_cluster: LoopbackCluster) -> None:
    with ray_session(loopback_cluster.address) as info:
        assert (info.nodes, info.cpus) == (2, 2.0)
        actors = [_Where.options(scheduling_strategy="SPREAD").remote() for _ in range(2)]
        nodes = ray.get([a.node.remote() for a in actors], timeout=120)
        assert len(set(nodes)) == 2, "both nodes host an actor"
        assert loopback_cluster.foreign_sockets(extra_pids=(os.getpid(),)) == []


def test_a_killed_node_is_declared_dead_and_can_be_replaced(
    loopback_cluster: LoopbackCluster,
) -> None:
    try:
        with ray_session(loopback_cluster.address):
            wait_for_nodes(2)
            loopback_cluster.kill_node(1)
            deadline = time.monotonic() + 60
            while sum(n["Alive"] for n in ray.nodes()) > 1:
                assert time.monotonic() < deadline, "the head never noticed the lost node"
                time.sleep(0.2)
    finally:
        loopback_cluster.restore()
    with ray_session(loopback_cluster.address):
        assert wait_for_nodes(2, timeout_s=60).nodes == 2


def test_stopping_leaves_no_process_and_no_folder() -> None:
    cluster = LoopbackCluster(nodes=1).start()
    pids, root = cluster.pids(), cluster.root
    assert pids and root is not None and root.is_dir()
    cluster.stop()
    alive = [p for p in pids if Path(f"/proc/{p}").exists() and _state(p) != "Z"]
    assert alive == []
    assert not root.exists()
    cluster.stop()  # twice is fine


LOCAL_RAY = """
import os, ray
from snakebot.cluster import ray_session
from snakebot.testing.cluster import foreign_sockets, process_tree

with ray_session(None, num_cpus=1) as info:
    assert (info.address, info.nodes, info.started_here) == (None, 1, True), info
    assert ray.get(ray.remote(lambda: 6 * 7).remote(), timeout=120) == 42
    tree = process_tree([os.getpid()])
    assert len(tree) > 3, tree  # Ray's GCS, raylet and a worker run under this process
    assert foreign_sockets(tree) == [], foreign_sockets(tree)
assert not ray.is_initialized()
print("ok")
"""


def test_ray_started_here_without_an_address_binds_loopback_only() -> None:
    # In a process of its own: Ray 2.60 started in a process turns token authentication on for
    # that process for good, and its later connections to a cluster without it fail.
    done = subprocess.run(
        [sys.executable, "-c", LOCAL_RAY],
        capture_output=True,
        text=True,
        timeout=300,
        env=node_environment(),
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip().endswith("ok")


def _state(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return "Z"
