"""Many runs side by side on one twin model with ``mujoco.batch``: the runner's cycle, batched.

The cycle is the runner's own (snakebot.control.cycle): the same ``CycleSchedule`` gives the
cycle times and the scored cycles, the same ``GaitCycle`` makes the commands. Each control cycle
sets every run's command, steps all live runs by one control period on a thread pool, and
samples what ``run_gait`` would read, with the positive work integrated over every physics step
as the twin integrates it (``readouts.step_work_j``). The states are bit-identical to
``TwinBackend`` stepping one run at a time (mujoco.batch guarantees it at any thread count), so
a tuned gait replays in ``snakebot run`` to the same metrics. Runs that fly, flip or diverge are
stopped early and stop costing time.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import batch as mj_batch

from snakebot.backends.twin import GroundFriction, TwinBackend
from snakebot.backends.twin.friction.scale import FrictionModel, ready_for_batch
from snakebot.backends.twin.model_builder import hold_ctrl_history, joint_name, link_name
from snakebot.backends.twin.readouts import (
    WARNING_NUMBER,
    Capsules,
    servo_torque_nm,
    step_work_j,
    unstable_count,
)
from snakebot.backends.twin.terrain import Terrain
from snakebot.config.schema import RobotConfig
from snakebot.control.cycle import CycleSchedule
from snakebot.tuning.commands import BatchCommands
from snakebot.tuning.feasibility import Envelope
from snakebot.tuning.trace import SAMPLES, FloatArray, Trace, make_trace

_STATE = mujoco.mjtState.mjSTATE_INTEGRATION
_RECORD = ("qpos", "qvel", "actuator_force", "subtree_com", "xquat", "geom_xpos", "geom_xmat")


@dataclass(frozen=True)
class TwinLayout:
    """Where the runner's quantities live in the twin's MjData."""

    qpos_index: np.ndarray
    dof_index: np.ndarray
    head_id: int
    capsules: Capsules

    def clearance_m(self, geom_xpos: FloatArray, geom_xmat: FloatArray) -> FloatArray:
        """Lowest point of the module capsules above z = 0 for MjData's ``geom_xpos`` (..., G, 3)
        and ``geom_xmat`` (..., G, 9): shape (...) (the twin's readout)."""
        return self.capsules.clearance_m(geom_xpos, geom_xmat)


def twin_layout(model: mujoco.MjModel, robot: RobotConfig) -> TwinLayout:
    """Indices of the joints, the head and the module capsules in a twin model of ``robot``."""
    joints = [model.joint(joint_name(i)).id for i in range(robot.joint_count)]
    return TwinLayout(
        qpos_index=model.jnt_qposadr[joints].copy(),
        dof_index=model.jnt_dofadr[joints].copy(),
        head_id=model.body(link_name(0)).id,
        capsules=Capsules.of_modules(model, robot.link_count),
    )


class TwinBatch:
    """Runs batches of commands on copies of one twin model, ``workers`` threads at a time.

    ``models`` (one per run) may replace the model per run, e.g. with other gains or servo
    parameters; they must come from the same robot so the layout matches.
    """

    def __init__(
        self,
        robot: RobotConfig,
        *,
        workers: int = 2,
        friction: GroundFriction | None = None,
        terrain: Terrain | None = None,
        friction_model: FrictionModel | None = None,
    ) -> None:
        self.robot = robot
        self.workers = max(1, workers)
        if robot.servo.physics.extras.changes_physics:
            warnings.warn(
                f"{robot.name}: battery sag and the overload protection (the servo model's "
                "battery_resistance_ohm, overload_trip_s) act between control periods of "
                "`snakebot run`; batched tuning and sysid replays leave them out, so a result "
                "may replay differently there (docs/physics.md)",
                stacklevel=2,
            )
        self.twin = TwinBackend(
            robot, friction=friction, terrain=terrain, friction_model=friction_model
        )
        self.twin.connect()
        ready_for_batch()  # a numpy scale-friction callback left in this process stops a batch
        model, data = self.twin.model, self.twin.data
        self.model = model
        self.initial_state = np.empty(mujoco.mj_stateSize(model, _STATE))
        mujoco.mj_getState(model, data, self.initial_state, _STATE)
        body = self.twin.body_state()
        self.start_com_m, self.start_head_quat = body.com_m, body.head_quat
        self.layout = twin_layout(model, robot)

    def initial_state_with_pose(
        self, joint_rad: FloatArray, command_rad: FloatArray | None = None
    ) -> FloatArray:
        """The start state with the joints bent to ``joint_rad`` (N,) and at rest.

        A delayed servo's past commands become ``command_rad`` (N,; default ``joint_rad``), the
        goals it held there, rather than the straight pose's zeros.
        """
        data = mujoco.MjData(self.model)
        mujoco.mj_setState(self.model, data, self.initial_state, _STATE)
        data.qpos[self.layout.qpos_index] = joint_rad
        hold_ctrl_history(self.model, data, joint_rad if command_rad is None else command_rad)
        mujoco.mj_forward(self.model, data)
        state = np.empty_like(self.initial_state)
        mujoco.mj_getState(self.model, data, state, _STATE)
        return state

    def run(
        self,
        commands: BatchCommands,
        duration_s: float,
        rate_hz: float,
        *,
        models: Sequence[mujoco.MjModel] | None = None,
        envelope: Envelope | None = None,
        initial_state: FloatArray | None = None,
    ) -> list[Trace]:
        """Run ``commands.size`` runs for ``duration_s`` at ``rate_hz``; one Trace per run.

        Open-loop commands go to MuJoCo a chunk of cycles at a time (one thread-pool pass per
        chunk instead of one per cycle); closed-loop ones one cycle at a time.
        """
        count = commands.size
        dt = 1.0 / rate_hz
        steps = self.twin.steps_for(dt)  # a ConfigError saying which rates fit
        schedule = CycleSchedule(
            rate_hz,
            duration_s,
            self.robot.safety.ramp_s,
            ramp_out=False,
            timestep_s=float(self.model.opt.timestep),
        )
        times = schedule.cycle_times(commands.length)
        batch = mj_batch.Batch(self.model, count, nthread=min(self.workers, count))
        if models is not None:
            batch.set_models(list(models))
        batch.state[:] = self.initial_state if initial_state is None else initial_state
        rec = _Recorder(count, len(times) - 1, self.robot.joint_count)
        per_run = list(models) if models is not None else [self.model] * count
        damping = np.stack([m.dof_damping[self.layout.dof_index] for m in per_run])
        lay = self.layout
        live = np.ones(count, dtype=bool)
        stopped_at = np.zeros(count, dtype=int)
        reasons = [""] * count
        check_every = max(1, round((envelope.stop_after_s if envelope else 1.0) * rate_hz))
        chunk = check_every if commands.open_loop else 1
        measured = batch.bind("qpos")[:, lay.qpos_index].copy()
        timestep = float(self.model.opt.timestep)
        work_total = np.zeros((count, self.robot.joint_count))  # as TwinBackend sums it
        commands.reset(measured, schedule)
        k = 0
        while k < len(times) - 1 and live.any():
            span = range(k, min(k + chunk, len(times) - 1))
            rows = [commands(c, times[c] - times[0], measured) for c in span]
            ids = np.flatnonzero(live)
            sent = np.stack([r[1] for r in rows], axis=1)  # (B, C, N)
            control = np.repeat(sent[ids], steps, axis=1)
            before = unstable_count(batch.warning[..., WARNING_NUMBER])
            try:
                out = batch.rollout(len(span) * steps, control=control, record=_RECORD, ids=ids)
            except mj_batch.SimulationError as exc:
                self._stop(exc.ids, "diverged", k, live, stopped_at, reasons)
                continue
            bad = ids[unstable_count(batch.warning[ids][..., WARNING_NUMBER]) > before[ids]]
            self._stop(bad, "diverged", k, live, stopped_at, reasons)
            end = {name: values[:, steps - 1 :: steps] for name, values in out.items()}
            position = end["qpos"][..., lay.qpos_index]
            velocity = end["qvel"][..., lay.dof_index]
            force = end["actuator_force"]
            per_step = (len(ids), len(span), steps, self.robot.joint_count)
            period_work = step_work_j(
                out["actuator_force"].reshape(per_step),
                damping[ids, None, :],
                out["qvel"][..., lay.dof_index].reshape(per_step),
                timestep,
            )
            cycle_work = np.empty_like(period_work)
            total = work_total[ids]
            for c in range(len(span)):  # the twin's running sum, then its per-cycle difference
                after = total + period_work[:, c]
                cycle_work[:, c] = after - total
                total = after
            work_total[ids] = total
            rec.store(
                ids,
                span,
                time_s=np.broadcast_to(times[span.start + 1 : span.stop + 1], position.shape[:2]),
                target=np.stack([r[0] for r in rows], axis=1)[ids],
                command=sent[ids],
                position=position,
                velocity=velocity,
                effort=servo_torque_nm(force, damping[ids, None, :], velocity),
                force=force,
                work=cycle_work,
                com=end["subtree_com"][:, :, lay.head_id],
                quat=end["xquat"][:, :, lay.head_id],
                clearance=lay.clearance_m(end["geom_xpos"], end["geom_xmat"]),
            )
            stopped_at[live] = span.stop
            measured[ids] = position[:, -1]
            k = span.stop
            if envelope is not None and k % check_every == 0:
                for reason, runs in rec.hopeless(k - 1, check_every, envelope, live).items():
                    self._stop(runs, reason, k, live, stopped_at, reasons)
        return [
            rec.trace(b, int(stopped_at[b]), dt, reasons[b], self.start_com_m, self.start_head_quat)
            for b in range(count)
        ]

    @staticmethod
    def _stop(
        runs: np.ndarray, reason: str, cycle: int, live: np.ndarray, at: np.ndarray, why: list[str]
    ) -> None:
        for b in np.asarray(runs, dtype=int):
            if live[b]:
                live[b] = False
                at[b] = cycle
                why[b] = reason


class _Recorder:
    """Preallocated (B, K, ...) sample arrays, cut into one Trace per run at the end."""

    def __init__(self, count: int, cycles: int, joints: int) -> None:
        self.arrays: dict[str, FloatArray] = {}
        for name, kind in SAMPLES.items():
            tail = () if not kind else (joints,) if kind == "n" else (int(kind),)
            self.arrays[name] = np.zeros((count, cycles, *tail))

    def store(self, runs: np.ndarray, cycles: range, **values: FloatArray) -> None:
        """Write (len(runs), len(cycles), ...) samples into their place."""
        for name, value in values.items():
            self.arrays[name][runs, cycles.start : cycles.stop] = value

    def hopeless(
        self, cycle: int, window: int, envelope: Envelope, live: np.ndarray
    ) -> dict[str, np.ndarray]:
        """Live runs that spent the whole last ``window`` cycles in flight or upside down."""
        span = slice(cycle + 1 - window, cycle + 1)
        airborne, flipped = envelope.hopeless(
            self.arrays["com"][:, span],
            self.arrays["clearance"][:, span],
            self.arrays["quat"][:, span],
        )
        return {
            "airborne": np.flatnonzero(live & airborne),
            "flipped": np.flatnonzero(live & flipped & ~airborne),
        }

    def trace(
        self, run: int, cycles: int, dt_s: float, reason: str, com: FloatArray, quat: FloatArray
    ) -> Trace:
        a = {name: values[run, :cycles].copy() for name, values in self.arrays.items()}
        return make_trace(a, dt_s, com, quat, reason)
