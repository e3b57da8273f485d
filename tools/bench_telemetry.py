"""What the telemetry sinks cost the control loop, per cycle (issue 13: must not disturb it).

Records 1000 cycles of snake12 sidewinding on the twin at 100 Hz, then replays them into each
sink set, timing every call (what the control thread pays): the CSV log alone, the Foxglove
server with no client, with a subscribed client (a thread here, so it competes for the CPU as a
local Foxglove app would), the MCAP file, the MCAP file in the ROS 2 encoding (``--mcap-encoding
ros2``), and CSV + server + client + MCAP. The scene is the
forward kinematics of the measured joints (the hardware path; the twin's own poses are cheaper).
Writes come at the control period (the loop waits on the bus or the pacer in between, when the
SDK's threads send); ``--period-ms 0`` writes back to back, the worst case. Rounds alternate the
sets so that the machine's load falls on all alike; medians and the 99th
percentile are pooled over the rounds, beside the twin's own cycle time.

    .venv/bin/python tools/bench_telemetry.py [--cycles 1000] [--rounds 2] [--period-ms 10]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.control.cycle import CycleRecord, CycleSink
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from snakebot.telemetry import CsvTelemetryWriter
from snakebot.telemetry.foxglove_live import FoxgloveTelemetry, Geometry, TelemetryOptions
from snakebot.telemetry.ros2_mcap import Ros2McapRecorder
from snakebot.telemetry.scene import KinematicLinkPoses
from snakebot.telemetry.sink import TelemetryTee


class Recorder:
    """Keeps every cycle's record the runner hands out, and the time between them (the twin's
    cycle)."""

    def __init__(self) -> None:
        self.rows: list[CycleRecord] = []
        self.cycle_s: list[float] = []
        self._last = time.perf_counter()

    def __call__(self, record: CycleRecord) -> None:
        now = time.perf_counter()
        self.cycle_s.append(now - self._last)
        self._last = now
        self.rows.append(record)


def record(cycles: int) -> Recorder:
    robot = load_robot("snake12")
    recorder = Recorder()
    gait = make_gait(
        "sidewinding", robot.joint_count, lower_rad=robot.lower_rad, upper_rad=robot.upper_rad
    )
    with TwinBackend(robot) as twin:
        metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
        run_gait(
            twin,
            gait,
            SafetyLayer.for_robot(robot),
            RunPlan(cycles / 100.0, 100.0, False),
            metrics,
            observers=[recorder],
        )
    return recorder


@contextlib.contextmanager
def client(port: int) -> Iterator[list[int]]:
    """A thread subscribed to every channel, counting the frames it gets."""
    from websockets.sync.client import connect

    received = [0]
    stop = threading.Event()
    ready = threading.Event()

    def run() -> None:
        with connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"]) as ws:
            channels: dict[str, int] = {}
            while len(channels) < 7:
                message = json.loads(ws.recv())
                if message["op"] == "advertise":
                    channels.update({c["topic"]: c["id"] for c in message["channels"]})
            ws.send(
                json.dumps(
                    {
                        "op": "subscribe",
                        "subscriptions": [
                            {"id": i, "channelId": c} for i, c in enumerate(channels.values(), 1)
                        ],
                    }
                )
            )
            ready.set()
            while not stop.is_set():
                with contextlib.suppress(TimeoutError):
                    if isinstance(ws.recv(timeout=0.1), bytes):
                        received[0] += 1

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    ready.wait(10)
    try:
        yield received
    finally:
        stop.set()
        thread.join(5)


def foxglove(folder: Path, *, port: bool, mcap: bool) -> FoxgloveTelemetry:
    robot = load_robot("snake12")
    poses = KinematicLinkPoses(robot)
    return FoxgloveTelemetry(
        TelemetryOptions(port=0 if port else None, mcap_path=folder / "b.mcap" if mcap else None),
        servo_ids=robot.servo_ids,
        rate_hz=100.0,
        drive=True,
        geometry=Geometry(
            robot.link_count, robot.link.length_m, robot.link.radius_m, lambda: poses
        ),
    )


def ros2_mcap(folder: Path) -> Ros2McapRecorder:
    robot = load_robot("snake12")
    poses = KinematicLinkPoses(robot)
    return Ros2McapRecorder(
        folder / "b.ros2.mcap",
        joint_names=[f"joint{i}" for i in range(robot.joint_count)],
        servo_ids=robot.servo_ids,
        rate_hz=100.0,
        geometry=Geometry(
            robot.link_count, robot.link.length_m, robot.link.radius_m, lambda: poses
        ),
    )


def replay(rows: list[CycleRecord], sink: CycleSink, period_s: float) -> list[float]:
    """Write every row at its cycle's deadline, as a loop waiting on the bus or the pacer does
    (the SDK's threads send while the loop waits); period 0 writes back to back."""
    costs = []
    deadline = time.perf_counter()
    for row in rows:
        start = time.perf_counter()
        sink(row)
        costs.append(time.perf_counter() - start)
        deadline += period_s
        pause = deadline - time.perf_counter()
        if pause > 0:
            time.sleep(pause)
    return costs


def measure(name: str, folder: Path, rows: list[CycleRecord], period_s: float) -> list[float]:
    csv: Callable[[], CsvTelemetryWriter] = lambda: CsvTelemetryWriter(folder / "b.csv", 12)  # noqa: E731
    if name == "CSV log":
        with csv() as sink:
            return replay(rows, sink, period_s)
    if name == "MCAP file":
        with foxglove(folder, port=False, mcap=True) as sink:
            return replay(rows, sink, period_s)
    if name == "MCAP file, ROS 2":
        with ros2_mcap(folder) as sink:
            return replay(rows, sink, period_s)
    with contextlib.ExitStack() as stack:
        fox = stack.enter_context(foxglove(folder, port=True, mcap=name.endswith("MCAP")))
        sinks: list[CycleSink] = [fox]
        if "client" in name:
            assert fox.port is not None
            got = stack.enter_context(client(fox.port))
        if name.startswith("CSV"):
            sinks.insert(0, stack.enter_context(csv()))
        costs = replay(rows, TelemetryTee(sinks), period_s)
        if "client" in name:
            time.sleep(0.5)
            assert got[0] > len(rows) // 2, f"the client got {got[0]} frames"
        return costs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cycles", type=int, default=1000)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument(
        "--period-ms",
        type=float,
        default=10.0,
        help="replay period (default 10: 100 Hz); 0: back to back",
    )
    args = parser.parse_args()
    recorder = record(args.cycles)
    names = [
        "CSV log",
        "Foxglove server, no client",
        "Foxglove server + client",
        "MCAP file",
        "MCAP file, ROS 2",
        "CSV + server + client + MCAP",
    ]
    results: dict[str, list[float]] = {name: [] for name in names}
    with tempfile.TemporaryDirectory() as folder:
        for _ in range(args.rounds):
            for name in names:
                results[name] += measure(name, Path(folder), recorder.rows, args.period_ms / 1e3)
    twin = np.array(recorder.cycle_s[1:]) * 1e3
    print(
        f"load average {' '.join(f'{x:.1f}' for x in os.getloadavg())} on {os.cpu_count()} "
        f"CPUs; {args.cycles} cycles x {args.rounds} rounds; snake12, writes every "
        f"{args.period_ms:g} ms (a 100 Hz cycle is 10 ms)"
    )
    print(
        f"{'twin step + gait + safety (context)':<36} median {np.median(twin):7.3f} ms  "
        f"p99 {np.percentile(twin, 99):7.3f} ms"
    )
    for name, costs in results.items():
        ms = np.array(costs) * 1e3
        print(
            f"{name:<36} median {np.median(ms):7.3f} ms  p99 {np.percentile(ms, 99):7.3f} ms"
            f"  mean {ms.mean():6.3f} ms = {ms.mean() / 10 * 100:4.1f} % of the cycle"
            f"  > 1 ms: {np.mean(ms > 1) * 100:4.1f} %"
        )


if __name__ == "__main__":
    main()
