"""A real multi-node Ray cluster on this machine that talks only over 127.0.0.1, for tests.

::

    from snakebot.cluster import ray_session
    from snakebot.testing.cluster import LoopbackCluster

    with LoopbackCluster(nodes=2) as cluster, ray_session(cluster.address):
        ...                       # Ray tasks and actors run on both nodes
        cluster.kill_node(1)      # node 1 dies as a machine would: SIGKILL, no goodbye

Each node is a ``ray start`` of its own (the head with ``--head --node-ip-address 127.0.0.1``,
the others with ``--address 127.0.0.1:PORT``), one CPU each, no dashboard, usage statistics off,
run through snakebot.cluster.raycli so Ray keeps 127.0.0.1 (on Linux Ray 2.60 swaps it for the
machine's outward address). Every port a node opens is given explicitly from a block found
free, so clusters of tests running side by side do not collide (Ray's defaults include fixed
ports, 8265 and 52365, even with the dashboard off). A node's processes share one process
group, and stopping kills those groups: ``ray stop`` would stop every Ray on the machine.
Linux only (process groups, /proc).
"""

from __future__ import annotations

import contextlib
import importlib.util
import json
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType

from snakebot.cluster.session import LOOPBACK
from snakebot.errors import ClusterError

_BLOCK = 64  # ports per node: named ones first, then Ray's worker ports
_PORT_RANGE = (20000, 32000)  # below Linux's ephemeral range, so no outgoing socket takes one
_NAMED = (
    "port",
    "dashboard-port",
    "ray-client-server-port",
    "node-manager-port",
    "object-manager-port",
    "runtime-env-agent-port",
    "dashboard-agent-listen-port",
    "dashboard-agent-grpc-port",
    "metrics-export-port",
)
_HEAD_ONLY = ("port", "dashboard-port", "ray-client-server-port")


@dataclass(frozen=True)
class Node:
    """One started node: its serial number (0 = head), the ``ray start`` process group, its
    folder and its ports."""

    index: int
    pgid: int
    temp_dir: Path
    ports: tuple[int, ...]


class LoopbackCluster:
    """``nodes`` Ray nodes on 127.0.0.1 with ``cpus_per_node`` CPUs each; a context manager.

    ``start_timeout_s`` bounds each ``ray start`` (a busy 2-core machine takes 5-20 s);
    ``node_timeout_s`` is about how long the head takes to declare a silent node dead.
    ClusterError when a node does not start; the nodes started so far are stopped then.
    """

    def __init__(
        self,
        nodes: int = 2,
        *,
        cpus_per_node: int = 1,
        object_store_bytes: int = 100 * 1024 * 1024,
        start_timeout_s: float = 180.0,
        node_timeout_s: float = 3.0,
    ) -> None:
        if nodes < 1:
            raise ValueError(f"a cluster needs at least one node, not {nodes}")
        self.node_count = nodes
        self.cpus_per_node = cpus_per_node
        self.object_store_bytes = object_store_bytes
        self.start_timeout_s = start_timeout_s
        # The head declares a silent node dead after about node_timeout_s (Ray's default is
        # 30 s), so a lost-node test does not wait half a minute for Ray to notice.
        period_ms = max(100, int(node_timeout_s * 1000 / 3))
        self.system_config = {
            "health_check_initial_delay_ms": period_ms,
            "health_check_period_ms": period_ms,
            "health_check_timeout_ms": period_ms,
            "health_check_failure_threshold": 3,
        }
        self.nodes: list[Node] = []
        self.killed: list[Node] = []
        self._started = 0  # nodes started so far: the next one's serial number
        self.root: Path | None = None
        self.gcs_port = 0

    @property
    def address(self) -> str:
        """``127.0.0.1:PORT`` of the head, what ``ray.init`` and ``--address`` take."""
        if not self.nodes:
            raise ClusterError(None, "the loopback cluster is not started")
        return f"{LOOPBACK}:{self.gcs_port}"

    def start(self) -> LoopbackCluster:
        """Start every node, head first; returns self."""
        # Short on purpose: Ray's unix sockets live under the temp folder (107-byte path limit).
        self.root = Path(tempfile.mkdtemp(prefix="sbray", dir="/tmp"))
        try:
            for _ in range(self.node_count):
                self.add_node()
        except BaseException:
            self.stop()
            raise
        return self

    def add_node(self) -> Node:
        """Start one more node (the head when there is none yet) and return it."""
        assert self.root is not None, "start() first"
        index = self._started
        self._started += 1
        ports = _free_block()
        named = dict(zip(_NAMED, ports, strict=False))
        if index == 0:
            self.gcs_port = named["port"]
        temp_dir = self.root / f"n{index}"
        temp_dir.mkdir()
        args = ["start", f"--num-cpus={self.cpus_per_node}", "--disable-usage-stats"]
        args += [f"--object-store-memory={self.object_store_bytes}", f"--temp-dir={temp_dir}"]
        if index == 0:
            args += ["--head", f"--node-ip-address={LOOPBACK}", "--include-dashboard=false"]
            args.append(f"--system-config={json.dumps(self.system_config)}")
        else:
            args += [f"--address={self.address}", f"--node-ip-address={LOOPBACK}"]
        for name, port in named.items():
            if name in _HEAD_ONLY and index > 0:
                continue
            if name == "ray-client-server-port" and importlib.util.find_spec("grpc") is None:
                continue  # Ray refuses the option without its client's gRPC package
            args.append(f"--{name}={port}")
        args += [f"--min-worker-port={ports[len(_NAMED)]}", f"--max-worker-port={ports[-1]}"]
        log = temp_dir / "ray-start.log"
        with log.open("wb") as out:
            process = subprocess.Popen(
                [sys.executable, "-m", "snakebot.cluster.raycli", *args],
                stdout=out,
                stderr=subprocess.STDOUT,
                env=node_environment(),
                start_new_session=True,
            )
        node = Node(index, process.pid, temp_dir, ports)
        self.nodes.append(node)
        try:
            code = process.wait(timeout=self.start_timeout_s)
        except subprocess.TimeoutExpired:
            code = None
        if code != 0:
            tail = log.read_text(errors="replace")[-2000:]
            raise ClusterError(
                self.address if index else None,
                f"node {index} did not start (ray start exit {code}); its log ends:\n{tail}",
            )
        return node

    def kill_node(self, index: int) -> None:
        """Kill every process of the live node ``index`` (0 = the head, which ends the cluster)
        at once with SIGKILL, as a lost machine would; it leaves ``nodes`` for ``killed``."""
        node = self.nodes.pop(index)
        self.killed.append(node)
        _kill_all(self._pids([node]))
        _kill_matching(str(node.temp_dir))
        _wait_gone(node.pgid, timeout_s=10.0)

    def restore(self) -> None:
        """Start a new node for each one killed, so the cluster has ``nodes`` live nodes again."""
        while self.killed:
            self.killed.pop()
            self.add_node()

    def pids(self) -> list[int]:
        """Every live process of the cluster's nodes: their ``ray start`` process groups and
        everything those started (Ray's workers run in sessions of their own)."""
        return self._pids(self.nodes)

    def _pids(self, nodes: list[Node]) -> list[int]:
        groups = {node.pgid for node in nodes}
        return process_tree(pid for pid, (_, pgid) in _processes().items() if pgid in groups)

    def foreign_sockets(self, extra_pids: tuple[int, ...] = ()) -> list[str]:
        """:func:`foreign_sockets` of the cluster's processes and ``extra_pids`` (the driver's)."""
        return foreign_sockets([*self.pids(), *extra_pids])

    def stop(self) -> None:
        """Kill every node, newest first, and remove their folders. Safe to call twice."""
        every = [*self.nodes, *self.killed]
        _kill_all(self._pids(every))
        for node in reversed(every):
            _sigkill(os.killpg, node.pgid)
        if self.root is not None:
            _kill_matching(str(self.root))
            for node in every:
                _wait_gone(node.pgid, timeout_s=10.0)
            shutil.rmtree(self.root, ignore_errors=True)
        self.nodes = []
        self.killed = []
        self._started = 0
        self.root = None

    def __enter__(self) -> LoopbackCluster:
        return self.start()

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.stop()


def process_tree(roots: Iterable[int]) -> list[int]:
    """``roots`` and every live process they started, and those started, and so on."""
    table = _processes()
    found = {pid for pid in roots if pid in table}
    grown = True
    while grown:
        children = {pid for pid, (ppid, _) in table.items() if ppid in found} - found
        found |= children
        grown = bool(children)
    return sorted(found)


def foreign_sockets(pids: Iterable[int]) -> list[str]:
    """Internet sockets (TCP, UDP; IPv4, IPv6) of ``pids`` bound to or connected to any address
    but loopback, ``'pid local -> remote'`` each; one listening on every interface counts."""
    inodes = _socket_table()
    found = []
    for pid in pids:
        for inode in _socket_inodes(pid):
            if inode in inodes:
                local, remote = inodes[inode]
                if not (_loopback_or_unset(local) and _loopback_or_unset(remote, remote=True)):
                    found.append(f"{pid} {local} -> {remote}")
    return found


def node_environment() -> dict[str, str]:
    """The environment a node runs in: this one, usage statistics and token authentication
    off (the nodes listen on loopback only), no proxy for loopback, and this snakebot first on
    the path, so the node's workers import the code under test."""
    import snakebot

    env = dict(os.environ)
    env["RAY_USAGE_STATS_ENABLED"] = "0"
    # Said outright: left unset, a head turns token authentication on when ~/.ray/auth_token
    # exists (any local `ray.init` writes one) and then refuses the nodes that join it.
    env["RAY_AUTH_MODE"] = "disabled"
    for name in ("no_proxy", "NO_PROXY"):
        env[name] = ",".join(filter(None, [env.get(name, ""), LOOPBACK, "localhost"]))
    source = str(Path(snakebot.__file__).resolve().parents[1])
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [source, env.get("PYTHONPATH", "")]))
    return env


def _free_block() -> tuple[int, ...]:
    """``_BLOCK`` consecutive ports on 127.0.0.1 that nothing listens on now."""
    rng = random.Random()
    for _ in range(200):
        base = rng.randrange(_PORT_RANGE[0], _PORT_RANGE[1] - _BLOCK)
        ports = tuple(range(base, base + _BLOCK))
        if all(_bindable(port) for port in ports):
            return ports
    raise ClusterError(None, f"no {_BLOCK} free ports in a row on {LOOPBACK}")


def _bindable(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        try:
            probe.bind((LOOPBACK, port))
        except OSError:
            return False
    return True


def _sigkill(send: Callable[[int, int], None], target: int) -> None:
    """SIGKILL ``target`` with ``send`` (os.kill a process, os.killpg a group), quietly when it
    is gone already or not ours."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        send(target, signal.SIGKILL)


def _kill_matching(text: str) -> None:
    """SIGKILL processes whose command line names ``text`` (this cluster's own folder), for
    any that left the node's process group."""
    matching = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit() or int(entry.name) == os.getpid():
            continue
        try:
            command = (entry / "cmdline").read_bytes().replace(b"\0", b" ")
        except OSError:
            continue
        if text.encode() in command:
            matching.append(int(entry.name))
    _kill_all(matching)


def _kill_all(pids: list[int]) -> None:
    for pid in pids:
        _sigkill(os.kill, pid)


def _processes() -> dict[int, tuple[int, int]]:
    """pid -> (parent pid, process group) of every live (not zombie) process."""
    out = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        fields = stat.rsplit(")", 1)[1].split()
        if fields[0] != "Z":
            out[int(entry.name)] = (int(fields[1]), int(fields[2]))
    return out


def _wait_gone(pgid: int, *, timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while any(g == pgid for _, g in _processes().values()) and time.monotonic() < deadline:
        time.sleep(0.05)


def _socket_table() -> dict[str, tuple[str, str]]:
    """Socket inode -> (local, remote) ``ADDRESS:PORT`` for IPv4 and IPv6 TCP and UDP."""
    table = {}
    for name in ("tcp", "tcp6", "udp", "udp6"):
        try:
            lines = Path(f"/proc/net/{name}").read_text().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            fields = line.split()
            table[fields[9]] = (_address(fields[1]), _address(fields[2]))
    return table


def _address(hex_text: str) -> str:
    """``/proc/net/tcp``'s ``0100007F:1F90`` as ``127.0.0.1:8080`` (IPv6 likewise)."""
    host, port = hex_text.split(":")
    raw = bytes.fromhex(host)
    # /proc prints each 32-bit word in host (little-endian) order.
    words = b"".join(raw[i : i + 4][::-1] for i in range(0, len(raw), 4))
    family = socket.AF_INET if len(words) == 4 else socket.AF_INET6
    return f"{socket.inet_ntop(family, words)}:{int(port, 16)}"


def _loopback_or_unset(address: str, *, remote: bool = False) -> bool:
    host = address.rsplit(":", 1)[0]
    if host.startswith("::ffff:"):
        host = host.removeprefix("::ffff:")
    if host in ("127.0.0.1", "::1") or host.startswith("127."):
        return True
    # An unconnected socket's remote end is all zeros; a local end of all zeros listens on
    # every interface, which is not loopback only.
    return remote and host in ("0.0.0.0", "::")


def _socket_inodes(pid: int) -> list[str]:
    out = []
    with contextlib.suppress(OSError):
        for fd in Path(f"/proc/{pid}/fd").iterdir():
            with contextlib.suppress(OSError):
                target = os.readlink(fd)
                if target.startswith("socket:["):
                    out.append(target[8:-1])
    return out
