"""The other way to use two cores: a process pool, each worker running the normal runner.

Kept to measure against ``engine.TwinBatch`` (docs/tuning.md has the numbers) and selectable with
``--engine processes``. Each worker builds its twin once per run; an ``on_cycle`` hook samples
the same quantities the batch engine records and stops hopeless runs early.
"""

from __future__ import annotations

import contextlib
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from snakebot.backends.twin import GroundFriction, TwinBackend
from snakebot.backends.twin.friction.scale import FrictionModel
from snakebot.backends.twin.terrain import Terrain
from snakebot.config.schema import RobotConfig
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import Gait, make_gait
from snakebot.tuning.engine import twin_layout
from snakebot.tuning.feasibility import Envelope
from snakebot.tuning.trace import FloatArray, Trace


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


class _Recording(Gait):
    """Delegates to a gait and keeps the last target it returned (before the safety layer)."""

    def __init__(self, gait: Gait) -> None:
        self.gait = gait
        self.joint_count = gait.joint_count
        self.last_target = np.zeros(gait.joint_count)

    @property
    def period_s(self) -> float | None:
        return self.gait.period_s

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        return self.gait.targets(time_s)

    def command(self, time_s: float, measured_rad: FloatArray | None = None) -> FloatArray:
        self.last_target = self.gait.command(time_s, measured_rad)
        return self.last_target

    def reset(self) -> None:
        self.gait.reset()


class _StopRunError(Exception):
    def __init__(self, reason: str) -> None:
        self.reason = reason


def run_job(job: PoolJob) -> Trace:
    """Run one job with ``run_gait`` on a fresh TwinBackend and return its samples."""
    robot = job.robot
    gait = _Recording(
        make_gait(
            job.gait,
            robot.joint_count,
            job.params,
            lower_rad=robot.lower_rad,
            upper_rad=robot.upper_rad,
        )
    )
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    plan = RunPlan(job.duration_s, job.rate_hz, ramp_out=False)
    twin = TwinBackend(
        robot, friction=job.friction, terrain=job.terrain, friction_model=job.friction_model
    )
    with contextlib.closing(twin):
        twin.connect()
        layout = twin_layout(twin.model, robot)
        start = twin.body_state()
        rows: list[list[np.ndarray]] = []
        window = max(1, round((job.envelope.stop_after_s if job.envelope else 1.0) * job.rate_hz))

        def sample(cycle: int, gait_time_s: float) -> None:
            data = twin.data
            state = twin.read_state()
            axis_z = np.abs(data.geom_xmat[layout.link_geoms, 8])
            lowest = data.geom_xpos[layout.link_geoms, 2] - layout.radius_m
            lowest = lowest - layout.half_length_m * axis_z
            rows.append(
                [
                    np.array([state.time_s]),
                    gait.last_target.copy(),
                    data.ctrl.copy(),
                    state.position_rad,
                    state.velocity_rad_s,
                    state.effort_nm,
                    data.actuator_force.copy(),
                    data.subtree_com[layout.head_id].copy(),
                    data.xquat[layout.head_id].copy(),
                    np.array([lowest.min()]),
                ]
            )
            if job.envelope is not None and cycle % window == 0:
                reason = _hopeless(rows[-window:], job.envelope)
                if reason:
                    raise _StopRunError(reason)

        reason = ""
        try:
            run_gait(twin, gait, SafetyLayer.for_robot(robot), plan, metrics, on_cycle=sample)
        except _StopRunError as stop:
            reason = stop.reason
    columns = [np.array(c) for c in zip(*rows, strict=True)] if rows else [np.zeros((0,))] * 10
    return Trace(
        dt_s=1.0 / job.rate_hz,
        time_s=columns[0].reshape(-1),
        target_rad=columns[1],
        command_rad=columns[2],
        position_rad=columns[3],
        velocity_rad_s=columns[4],
        effort_nm=columns[5],
        actuator_force_nm=columns[6],
        com_m=columns[7],
        head_quat=columns[8],
        clearance_m=columns[9].reshape(-1),
        start_com_m=start.com_m,
        start_head_quat=start.head_quat,
        stop_reason=reason,
    )


def _hopeless(rows: Sequence[list[np.ndarray]], envelope: Envelope) -> str:
    com_z = np.array([row[7][2] for row in rows])
    clearance = np.array([row[9][0] for row in rows])
    if envelope.airborne(com_z, clearance).all():
        return "airborne"
    quat = np.array([row[8] for row in rows])
    up_z = 1.0 - 2.0 * (quat[:, 1] ** 2 + quat[:, 2] ** 2)
    return "flipped" if envelope.flipped(up_z).all() else ""


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
