"""Running snakebot's searches on a Ray cluster (the ``cluster`` extra).

The one package that imports ``ray``, and only inside functions, so importing it stays light:
:func:`connect` joins a cluster (or starts Ray on this machine), :func:`ray_session` does so for
a ``with`` block. docs/cluster.md shows how to run searches on a cluster of your own.
"""

from __future__ import annotations

from snakebot.cluster.session import (
    INSTALL,
    ClusterInfo,
    cluster_info,
    connect,
    disconnect,
    is_loopback,
    keep_loopback,
    ray_session,
    require_ray,
    wait_for_nodes,
)

__all__ = [
    "INSTALL",
    "ClusterInfo",
    "cluster_info",
    "connect",
    "disconnect",
    "is_loopback",
    "keep_loopback",
    "ray_session",
    "require_ray",
    "wait_for_nodes",
]
