"""Connecting to a Ray cluster, or starting Ray on this machine: the one door to Ray.

``connect(None)`` starts Ray on this machine's cores (a laptop: ``--executor ray`` with no
address), bound to 127.0.0.1 only; ``connect("HOST:PORT")`` joins a running cluster that was
started with ``ray start --head``. Ray rewrites a loopback host (127.0.0.1, localhost) to the
machine's outward address before it connects (``ray._private.services.resolve_ip_for_localhost``,
Ray 2.60); a cluster started on loopback only (snakebot.testing.cluster.LoopbackCluster) does not
listen there, so :func:`keep_loopback` switches that rewrite off while connecting to it.
"""

from __future__ import annotations

import contextlib
import ipaddress
import logging
import os
import time
from collections.abc import Iterator
from dataclasses import dataclass
from types import ModuleType
from typing import Any

from snakebot.errors import ClusterError, MissingDependencyError

INSTALL = "pip install 'snakebot[cluster]'"
LOOPBACK = "127.0.0.1"
_RAY_SETS = ("RAY_AUTH_MODE",)
"""Environment variables ``ray.init`` sets in the driver's own process."""
_saved_env: dict[str, str | None] = {}


@dataclass(frozen=True)
class ClusterInfo:
    """The cluster a driver is connected to: its address, live nodes and CPUs.

    ``address`` is ``None`` when snakebot started Ray on this machine (no address given).
    """

    address: str | None
    nodes: int
    cpus: float
    started_here: bool


def require_ray() -> ModuleType:
    """The ``ray`` module; MissingDependencyError with the install command when it is missing."""
    try:
        import ray
    except ImportError as exc:
        raise MissingDependencyError(f"the Ray executor needs Ray: {INSTALL}") from exc
    module: ModuleType = ray
    return module


def is_loopback(address: str) -> bool:
    """True when ``address`` (``HOST`` or ``HOST:PORT``) names this machine's loopback."""
    if address.startswith("["):  # [IPv6]:PORT
        host = address[1:].split("]", 1)[0]
    elif address.count(":") == 1:  # HOST:PORT
        host = address.rsplit(":", 1)[0]
    else:  # HOST, or a bare IPv6 address
        host = address
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@contextlib.contextmanager
def keep_loopback() -> Iterator[None]:
    """Within the block, Ray leaves 127.0.0.1 and localhost as they are instead of swapping in
    the machine's outward address (the ``resolve_ip_for_localhost`` of Ray 2.60's services)."""
    services = require_ray()._private.services
    original = services.resolve_ip_for_localhost
    services.resolve_ip_for_localhost = lambda host: host
    try:
        yield
    finally:
        services.resolve_ip_for_localhost = original


def connect(address: str | None = None, *, num_cpus: int | None = None) -> ClusterInfo:
    """Join the Ray cluster at ``address`` (``HOST:PORT`` of its head, or ``auto``), or start
    Ray on this machine with ``num_cpus`` CPUs (default: all) when ``address`` is None.

    A driver already connected (``ray.init`` called before) stays as it is. Raises
    MissingDependencyError without Ray, ClusterError when the cluster cannot be reached.
    """
    ray = require_ray()
    if ray.is_initialized():
        return cluster_info(address, started_here=False)
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    options: dict[str, Any] = {"logging_level": logging.WARNING, "log_to_driver": True}
    if address is None:
        options |= {"num_cpus": num_cpus, "include_dashboard": False}
    else:
        options["address"] = address
    local = address is None or is_loopback(address)
    if local:
        options["_node_ip_address"] = LOOPBACK
    _saved_env.clear()
    _saved_env.update({name: os.environ.get(name) for name in _RAY_SETS})
    try:
        with keep_loopback() if local else contextlib.nullcontext():
            ray.init(**options)
    except (ConnectionError, RuntimeError, ValueError) as exc:
        _restore_env()
        raise ClusterError(address, f"cannot connect: {exc}") from exc
    return cluster_info(address, started_here=True)


def cluster_info(address: str | None, *, started_here: bool) -> ClusterInfo:
    """The live nodes and CPUs of the cluster this driver is connected to."""
    ray = require_ray()
    alive = [node for node in ray.nodes() if node.get("Alive")]
    cpus = sum(float(node.get("Resources", {}).get("CPU", 0.0)) for node in alive)
    return ClusterInfo(address, len(alive), cpus, started_here)


def wait_for_nodes(count: int, *, timeout_s: float = 60.0) -> ClusterInfo:
    """Wait until the connected cluster has ``count`` live nodes; ClusterError after
    ``timeout_s`` seconds."""
    deadline = time.monotonic() + timeout_s
    while True:
        info = cluster_info(None, started_here=False)
        if info.nodes >= count:
            return info
        if time.monotonic() > deadline:
            raise ClusterError(None, f"{info.nodes} live nodes after {timeout_s:g} s, not {count}")
        time.sleep(0.2)


def disconnect() -> None:
    """Disconnect this driver from Ray (and stop Ray when it was started here), leaving the
    process's Ray settings as they were before :func:`connect`."""
    ray = require_ray()
    if ray.is_initialized():
        ray.shutdown()
    _restore_env()


def _restore_env() -> None:
    """Undo what ``ray.init`` set in this process's environment, so that processes started
    later do not inherit it: starting Ray here sets ``RAY_AUTH_MODE=token`` (Ray 2.60). Ray's
    core keeps token authentication on in this process all the same, and a later connection of
    the same process to a cluster without it creates no actor (docs/cluster.md)."""
    for name, value in _saved_env.items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value
    _saved_env.clear()


@contextlib.contextmanager
def ray_session(
    address: str | None = None, *, num_cpus: int | None = None
) -> Iterator[ClusterInfo]:
    """:func:`connect` for the block; disconnects at the end unless the driver was already
    connected before it."""
    info = connect(address, num_cpus=num_cpus)
    try:
        yield info
    finally:
        if info.started_here:
            disconnect()
