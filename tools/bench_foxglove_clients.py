"""A 100 Hz bus run with and without a swarm of hostile Foxglove clients, side by side.

Starts ``snakebot emulate --pty`` and ``--hogs`` CPU-bound processes, then runs ``snakebot run
--backend dynamixel --port PTY --foxglove=0 --log x.csv`` ``--pairs`` times in each arm,
alternating the order (without, with; with, without; ...). In the "with" arm, ``--clients``
WebSocket clients on 127.0.0.1 connect as soon as the server prints its URL, subscribe to every
channel and never read again (with ``--retry-s S``, a client that is refused tries again S
seconds later, so the swarm keeps pressing for the whole run). The swarm is this file in a
process of its own that imports neither numpy nor snakebot. Each run's rate and gaps come from
its CSV's time column, and the CPU seconds the run process used from /proc (a figure a loaded
machine disturbs less than the rate); the report gives each run and the medians of each arm, the
load average, and what the server did with the clients (the run summary's ``foxglove_clients``).
The hogs, the swarm and the emulator are stopped on every exit path (including Ctrl-C).

``--write-cost`` measures instead, in this process, what handing one cycle's record to
``FoxgloveTelemetry`` costs the control thread (median and 99th percentile, paced at 100 Hz for
``--duration`` s) and the CPU seconds of the whole process (every thread: the SDK's, the
gate's), with and without the swarm; a loaded machine disturbs these figures far less than a
bus run's rate.

Usage::

    python tools/bench_foxglove_clients.py                       # 200 clients, 3 pairs, 20 s
    python tools/bench_foxglove_clients.py --pairs 5 --duration 30 --json
    python tools/bench_foxglove_clients.py --write-cost --pairs 3 --duration 10

Exit status: 0 when the "with" arm keeps >= 95 % of the other's median rate and has no more
gaps over 50 ms (median) than it; 1 otherwise.
"""

from __future__ import annotations

import argparse
import asyncio
import base64
import contextlib
import json
import os
import re
import select
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

_SPIN = "while True:\n    pass\n"
GAP_S = 0.05


@dataclass(frozen=True)
class RunResult:
    """One bus run: its arm, the achieved rate (Hz), gaps over 50 ms, the longest gap (s), the
    rate in each quarter of the run (Hz), the CPU seconds of the ``snakebot run`` process (all
    its threads, up to its last 0.2 s), the load average before it, the exit status and what
    the server did with its clients."""

    arm: str
    rate_hz: float
    gaps_over_50ms: int
    max_gap_s: float
    rate_by_quarter_hz: list[float]
    cpu_s: float
    load_before: float
    returncode: int
    clients: dict[str, int]


def snakebot(*argv: str, **kwargs: Any) -> subprocess.Popen[str]:
    """``python -m snakebot ARGV`` from a neutral folder: the snakebot it runs is the one
    PYTHONPATH (or the installed package) names, never whichever the current folder holds."""
    return subprocess.Popen(
        [sys.executable, "-m", "snakebot", *argv], text=True, cwd=tempfile.gettempdir(), **kwargs
    )


@contextlib.contextmanager
def running(procs: list[subprocess.Popen[Any]]) -> Iterator[None]:
    """Interrupt, then kill, every process in ``procs`` on the way out."""
    try:
        yield
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
        for proc in procs:
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


class CpuWatch:
    """Samples a process's CPU seconds (user + system, /proc) every 0.2 s until it exits."""

    def __init__(self, pid: int) -> None:
        self.cpu_s = 0.0
        self._path = Path(f"/proc/{pid}/stat")
        self._thread = threading.Thread(target=self._watch, daemon=True)
        self._thread.start()

    def _watch(self) -> None:
        ticks = os.sysconf("SC_CLK_TCK")
        while True:
            try:
                fields = self._path.read_text().rsplit(")", 1)[1].split()
            except (OSError, IndexError):
                return
            if fields[0] == "Z":
                return
            self.cpu_s = (int(fields[11]) + int(fields[12])) / ticks
            time.sleep(0.2)

    def result(self) -> float:
        self._thread.join(timeout=5)
        return round(self.cpu_s, 2)


def emulator_port(proc: subprocess.Popen[str]) -> str:
    assert proc.stdout is not None
    ready, _, _ = select.select([proc.stdout], [], [], 120.0)
    if not ready:
        raise SystemExit("bench_foxglove_clients: the emulator printed nothing in 120 s")
    return str(json.loads(proc.stdout.readline())["port"])


def one_run(arm: str, port: str, args: argparse.Namespace, folder: Path, index: int) -> RunResult:
    """One ``snakebot run`` over the bus; in the "with" arm, the swarm against its server."""
    import numpy as np  # not in the swarm's process

    from snakebot.telemetry import read_log

    log = folder / f"run{index:02d}-{arm}.csv"
    load_before = os.getloadavg()[0]
    proc = snakebot(
        "run",
        "--backend",
        "dynamixel",
        "--port",
        port,
        "--robot",
        args.robot,
        "--gait",
        args.gait,
        "--duration",
        str(args.duration),
        "--rate",
        "100",
        "--foxglove=0",
        "--log",
        str(log),
        "--json",
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    swarm: list[subprocess.Popen[Any]] = []
    cpu = CpuWatch(proc.pid)
    with running([proc]):
        assert proc.stderr is not None
        line = proc.stderr.readline()
        match = re.search(r"ws://\S+:\d+", line)
        if match is None:
            raise SystemExit(f"bench_foxglove_clients: no server URL from the run: {line!r}")
        if arm == "with":
            swarm.append(
                subprocess.Popen(
                    [
                        sys.executable,
                        os.path.abspath(__file__),
                        "--swarm",
                        match.group(0),
                        "--clients",
                        str(args.clients),
                        "--retry-s",
                        str(args.retry_s),
                    ],
                )
            )
        with running(swarm):
            stdout, stderr = proc.communicate(timeout=args.duration + 180)
    summary = json.loads(stdout) if proc.returncode in (0, 130) and stdout.strip() else {}
    if proc.returncode != 0:
        print(
            f"  run {index} ({arm}) exit {proc.returncode}: {stderr.strip()[-400:]}",
            file=sys.stderr,
        )
    times = read_log(log).column("time_s") if log.exists() else np.zeros(0)
    gaps = np.diff(times)
    rate = (len(times) - 1) / float(times[-1] - times[0]) if len(times) > 1 else 0.0
    quarters = []
    if len(times) > 8:
        edges = np.linspace(times[0], times[-1], 5)
        counts = np.histogram(times, edges)[0]
        quarters = [round(float(c) / float(edges[1] - edges[0]), 1) for c in counts]
    return RunResult(
        arm,
        round(rate, 2),
        int(np.sum(gaps > GAP_S)),
        round(float(gaps.max()), 4) if len(gaps) else 0.0,
        quarters,
        cpu.result(),
        round(load_before, 2),
        proc.returncode,
        summary.get("foxglove_clients", {}),
    )


def bench(args: argparse.Namespace) -> list[RunResult]:
    """The alternating series, beside ``args.hogs`` hogs and one emulator, all stopped after."""
    hogs = [
        subprocess.Popen([sys.executable, "-c", _SPIN], stderr=subprocess.DEVNULL)
        for _ in range(args.hogs)
    ]  # an interrupted hog has nothing to say
    results: list[RunResult] = []
    with running(hogs), tempfile.TemporaryDirectory() as tmp:
        emulator = snakebot(
            "emulate",
            "--pty",
            "--json",
            "--robot",
            args.robot,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
        )
        with running([emulator]):
            port = emulator_port(emulator)
            for pair in range(args.pairs):
                order = ("without", "with") if pair % 2 == 0 else ("with", "without")
                for arm in order:
                    result = one_run(arm, port, args, Path(tmp), len(results) + 1)
                    results.append(result)
                    print(
                        f"run {len(results)} {arm:7s} {result.rate_hz:6.2f} Hz, "
                        f"{result.gaps_over_50ms} gaps > 50 ms, longest "
                        f"{result.max_gap_s * 1e3:.0f} ms, by quarter "
                        f"{result.rate_by_quarter_hz} Hz, {result.cpu_s:.1f} CPU s, "
                        f"load {result.load_before:.1f}, "
                        f"exit {result.returncode}, clients {result.clients}",
                        flush=True,
                    )
    return results


def write_cost(args: argparse.Namespace) -> list[dict[str, Any]]:
    """Per-write cost and process CPU over ``args.duration`` s at 100 Hz, each arm in turn."""
    import numpy as np

    from snakebot.control.cycle import CycleRecord
    from snakebot.telemetry.foxglove_live import FoxgloveTelemetry, TelemetryOptions
    from snakebot.types import JointState

    rows = []
    rng = np.random.default_rng(0)
    for pair in range(args.pairs):
        for arm in ("without", "with") if pair % 2 == 0 else ("with", "without"):
            sink = FoxgloveTelemetry(
                TelemetryOptions(port=0), servo_ids=range(1, 13), rate_hz=100.0
            )
            swarm: list[subprocess.Popen[Any]] = []
            if arm == "with":
                swarm.append(
                    subprocess.Popen(
                        [
                            sys.executable,
                            os.path.abspath(__file__),
                            "--swarm",
                            f"ws://127.0.0.1:{sink.port}",
                            "--clients",
                            str(args.clients),
                            "--retry-s",
                            str(args.retry_s),
                        ],
                    )
                )
            with running(swarm), contextlib.closing(sink):
                time.sleep(3.0)  # the swarm connects and subscribes
                took = []
                cpu0, start = time.process_time(), time.monotonic()
                cycles = round(args.duration * 100)
                for cycle in range(cycles):
                    values = rng.normal(size=(4, 12))
                    state = JointState(cycle / 100, values[1], values[2], values[3])
                    record = CycleRecord(
                        cycle + 1,
                        state.time_s,
                        values[0],
                        values[0],
                        state,
                        None,
                        1,
                        True,
                        0.01,
                        False,
                        100,
                    )
                    began = time.perf_counter()
                    sink(record)
                    took.append(time.perf_counter() - began)
                    time.sleep(max(0.0, start + (cycle + 1) / 100 - time.monotonic()))
                cpu = time.process_time() - cpu0
                clients = sink.client_counts() if hasattr(sink, "client_counts") else {}
            row = {
                "arm": arm,
                "write_median_ms": round(float(np.median(took)) * 1e3, 3),
                "write_p99_ms": round(float(np.percentile(took, 99)) * 1e3, 3),
                "write_max_ms": round(max(took) * 1e3, 1),
                "cpu_s": round(cpu, 2),
                "load": round(os.getloadavg()[0], 1),
                "clients": clients,
            }
            rows.append(row)
            print(
                f"{arm:7s} write median {row['write_median_ms']:.3f} ms, p99 "
                f"{row['write_p99_ms']:.3f} ms, max {row['write_max_ms']:.1f} ms; process "
                f"CPU {row['cpu_s']:.2f} s over {args.duration:g} s; load {row['load']}; "
                f"{clients}",
                flush=True,
            )
    for arm in ("without", "with"):
        mine = [r for r in rows if r["arm"] == arm]
        print(
            f"median {arm:7s} write {statistics.median(r['write_median_ms'] for r in mine):.3f}"
            f" ms (p99 {statistics.median(r['write_p99_ms'] for r in mine):.3f} ms), process "
            f"CPU {statistics.median(r['cpu_s'] for r in mine):.2f} s"
        )
    return rows


# -- the swarm: never-reading clients ---------------------------------------------------------


async def _hostile(host: str, port: int, path: str, retry_s: float) -> None:
    """Connect, subscribe to every channel, never read again; when refused, again in
    ``retry_s`` seconds (0: give up)."""
    while True:
        try:
            reader, writer = await asyncio.open_connection(host, port)
        except OSError:
            if not retry_s:
                return
            await asyncio.sleep(retry_s)
            continue
        key = base64.b64encode(os.urandom(16)).decode()
        writer.write(
            f"GET {path} HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
            f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
            "Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n".encode()
        )
        try:
            head = await asyncio.wait_for(reader.readuntil(b"\r\n\r\n"), 10.0)
            if not head.startswith(b"HTTP/1.1 101"):
                raise ConnectionError("refused")
            channels: list[int] = []
            while not channels:
                message = json.loads(await _frame(reader))
                if message.get("op") == "advertise":
                    channels = [channel["id"] for channel in message["channels"]]
            subscribe = {
                "op": "subscribe",
                "subscriptions": [{"id": n, "channelId": c} for n, c in enumerate(channels, 1)],
            }
            writer.write(_masked(json.dumps(subscribe).encode()))
            await writer.drain()
            await asyncio.sleep(1e9)  # and never read again
        except (ConnectionError, OSError, TimeoutError, asyncio.IncompleteReadError, ValueError):
            writer.close()
            if not retry_s:
                await asyncio.sleep(1e9)  # stay, as a refused client that does nothing
            await asyncio.sleep(retry_s)


async def _frame(reader: asyncio.StreamReader) -> bytes:
    head = await reader.readexactly(2)
    length = head[1] & 0x7F
    if length == 126:
        length = int.from_bytes(await reader.readexactly(2), "big")
    elif length == 127:
        length = int.from_bytes(await reader.readexactly(8), "big")
    return await reader.readexactly(length)


def _masked(payload: bytes) -> bytes:
    mask = os.urandom(4)
    size = len(payload)
    length = bytes([0x80 | size]) if size < 126 else bytes([0xFE]) + size.to_bytes(2, "big")
    return b"\x81" + length + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload))


def swarm(url: str, clients: int, retry_s: float) -> None:
    """Run ``clients`` hostile clients against ``url`` until interrupted."""
    match = re.fullmatch(r"ws://\[?([^\]/]+)\]?:(\d+)(/.*)?", url)
    if match is None:
        raise SystemExit(f"bench_foxglove_clients: not a ws:// URL: {url}")
    host, port, path = match.group(1), int(match.group(2)), match.group(3) or "/"

    async def all_of_them() -> None:
        await asyncio.gather(*(_hostile(host, port, path, retry_s) for _ in range(clients)))

    with contextlib.suppress(KeyboardInterrupt):
        asyncio.run(all_of_them())


def main(argv: list[str] | None = None) -> int:
    """Parse arguments, run the series (or be the swarm), print the report."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clients", type=int, default=200, help="hostile clients (default 200)")
    parser.add_argument("--pairs", type=int, default=3, help="runs per arm (default 3)")
    parser.add_argument("--duration", type=float, default=20.0, help="seconds per run (20)")
    parser.add_argument("--hogs", type=int, default=2, help="CPU-bound processes (default 2)")
    parser.add_argument("--robot", default="snake12", help="robot (default snake12)")
    parser.add_argument("--gait", default="sidewinding", help="gait (default sidewinding)")
    parser.add_argument(
        "--retry-s",
        type=float,
        default=0.0,
        metavar="S",
        help="a refused client tries again S seconds later (default 0: never)",
    )
    parser.add_argument("--json", action="store_true", help="print the runs as JSON at the end")
    parser.add_argument(
        "--write-cost",
        action="store_true",
        help="measure one write's cost and the process CPU, in this process",
    )
    parser.add_argument("--swarm", metavar="URL", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.swarm:
        swarm(args.swarm, args.clients, args.retry_s)
        return 0
    if args.pairs < 1 or args.clients < 1 or args.hogs < 0:
        parser.error("--pairs and --clients must be at least 1, --hogs at least 0")
    if args.write_cost:
        rows = write_cost(args)
        if args.json:
            print(json.dumps(rows, indent=2))
        return 0
    results = bench(args)
    arms = {arm: [r for r in results if r.arm == arm] for arm in ("without", "with")}
    medians = {
        arm: {
            "rate_hz": statistics.median(r.rate_hz for r in runs),
            "gaps_over_50ms": statistics.median(r.gaps_over_50ms for r in runs),
            "max_gap_s": statistics.median(r.max_gap_s for r in runs),
            "cpu_s": statistics.median(r.cpu_s for r in runs),
        }
        for arm, runs in arms.items()
    }
    kept = medians["with"]["rate_hz"] / medians["without"]["rate_hz"]
    ok = kept >= 0.95 and medians["with"]["gaps_over_50ms"] <= medians["without"]["gaps_over_50ms"]
    for arm, median in medians.items():
        print(
            f"median {arm:7s} {median['rate_hz']:.2f} Hz, {median['gaps_over_50ms']:g} gaps "
            f"> 50 ms, longest {median['max_gap_s'] * 1e3:.0f} ms, {median['cpu_s']:.1f} CPU s"
        )
    print(
        f"with {args.clients} clients and {args.hogs} hogs: {kept:.1%} of the rate "
        f"({'ok' if ok else 'NOT ok'}); load average now {os.getloadavg()[0]:.1f}, "
        f"{os.cpu_count()} CPUs"
    )
    if args.json:
        print(
            json.dumps(
                {"runs": [asdict(r) for r in results], "medians": medians, "kept": kept, "ok": ok},
                indent=2,
            )
        )
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
