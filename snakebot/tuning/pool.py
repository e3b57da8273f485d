"""The other way to use two cores: a process pool, each worker running the normal runner.

Kept to measure against ``engine.TwinBatch`` (docs/tuning.md has the numbers) and selectable with
``--engine processes``. Each worker builds its twin once per run; an observer of the runner's
cycle records samples the batch engine's layout (snakebot.tuning.trace.SAMPLES) and stops
hopeless runs early with the same envelope test.
"""

from __future__ import annotations

import contextlib
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

from snakebot.backends.twin import GroundFriction, TwinBackend
from snakebot.backends.twin.friction.scale import FrictionModel
from snakebot.backends.twin.terrain import Terrain
from snakebot.config.schema import RobotConfig
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from snakebot.tuning.engine import twin_layout
from snakebot.tuning.feasibility import Envelope
from snakebot.tuning.trace import Trace, TraceRows, make_trace


@dataclass(frozen=True)
class PoolJob:
    """One run for a worker: the robot, a gait by name and parameters, and the plan."""

    robot: RobotConfig
    gait: str
    params: Mapping[str, object]
    duration_s: float
    rate_hz: float
    envelope: Envelope | None
    friction: GroundFriction | None = None
    terrain: Terrain | None = None
    friction_model: FrictionModel | None = None


class _StopRunError(Exception):
    def __init__(self, reason: str) -> None:
        self.reason = reason


def run_job(job: PoolJob) -> Trace:
    """Run one job with ``run_gait`` on a fresh TwinBackend and return its samples."""
    robot = job.robot
    gait = make_gait(
        job.gait,
        robot.joint_count,
        job.params,
        lower_rad=robot.lower_rad,
        upper_rad=robot.upper_rad,
    )
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    plan = RunPlan(job.duration_s, job.rate_hz, ramp_out=False)
    twin = TwinBackend(
        robot, friction=job.friction, terrain=job.terrain, friction_model=job.friction_model
    )
    rows = TraceRows(robot.joint_count)
    window = max(1, round((job.envelope.stop_after_s if job.envelope else 1.0) * job.rate_hz))
    with contextlib.closing(twin):
        twin.connect()
        layout = twin_layout(twin.model, robot)
        start = twin.body_state()

        def sample(record: CycleRecord) -> None:
            data = twin.data
            clearance = layout.clearance_m(data.geom_xpos, data.geom_xmat)
            rows.add(record, data.actuator_force.copy(), float(clearance))
            if job.envelope is not None and record.cycle % window == 0:
                last = rows.arrays(window)
                airborne, flipped = job.envelope.hopeless(
                    last["com"], last["clearance"], last["quat"]
                )
                if airborne or flipped:
                    raise _StopRunError("airborne" if airborne else "flipped")

        reason = ""
        try:
            run_gait(twin, gait, SafetyLayer.for_robot(robot), plan, metrics, observers=[sample])
        except _StopRunError as stop:
            reason = stop.reason
    return make_trace(rows.arrays(), 1.0 / job.rate_hz, start.com_m, start.head_quat, reason)


class ProcessPool:
    """``workers`` processes running ``run_job``; use as a context manager."""

    def __init__(self, workers: int = 2) -> None:
        self._executor = ProcessPoolExecutor(max_workers=max(1, workers))

    def run(self, jobs: Sequence[PoolJob]) -> list[Trace]:
        """Run the jobs across the workers; results in job order."""
        return list(self._executor.map(run_job, jobs))

    def close(self) -> None:
        """Stop the worker processes."""
        self._executor.shutdown(cancel_futures=True)

    def __enter__(self) -> ProcessPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
