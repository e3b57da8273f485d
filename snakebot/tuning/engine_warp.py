"""Every candidate of a generation as one world of one batched MuJoCo Warp model (`--engine warp`).

The cycle is the CPU engine's (snakebot.tuning.engine.TwinBatch): the same ``CycleSchedule``,
the same ``GaitCommands`` through the safety layer, the same control period of whole physics
steps. The physics is MuJoCo Warp's (float32, its own Newton solver), so runs agree with the
CPU engine to a measured tolerance, not to the bit (docs/tuning.md has the table). What the CPU
engine records as a trace and scores on the host is folded into a few running values per world
on the device (snakebot.tuning.warp_kernels); only those come back.

Needs the ``gpu`` extra (``mujoco-warp``, ``warp-lang``); runs on Warp's CPU device too.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from snakebot.control.cycle import CycleSchedule
from snakebot.control.metrics import head_yaw_rad
from snakebot.errors import ConfigError, MissingDependencyError
from snakebot.gaits import Gait
from snakebot.gaits.spec import ParamValue
from snakebot.tuning.commands import BatchCommands, GaitCommands
from snakebot.tuning.engine import TwinBatch
from snakebot.tuning.feasibility import (
    FLIPPED_UP_Z,
    MOVING_FRACTION,
    SATURATION_FRACTION,
    Envelope,
    Violations,
)
from snakebot.tuning.problem import EvalPlan, GaitProblem
from snakebot.tuning.trace import FloatArray
from snakebot.tuning.warp_scores import outcomes

INSTALL = "pip install 'snakebot[gpu]'"
DEVICES = ("cpu", "cuda")
TABLE_CYCLES = 100  # open-loop gaits: targets of this many cycles per Gait.targets call
_STATE = mujoco.mjtState.mjSTATE_INTEGRATION
STOP_REASONS = ("", "airborne", "flipped", "diverged")
"""Why a world stopped, by warp_kernels' stop code."""

assert FLIPPED_UP_Z == -0.5  # warp_kernels.accumulate has the same threshold inline


def require_warp() -> tuple[Any, Any]:
    """``(warp, mujoco_warp)``; MissingDependencyError with the install command when missing."""
    try:
        import warp

        # Before MuJoCo Warp initialises Warp: no banner, no line per kernel module loaded.
        warp.config.log_level = warp.LOG_WARNING
        import mujoco_warp
    except ImportError as exc:
        raise MissingDependencyError(
            f"the warp engine needs MuJoCo Warp (mujoco-warp, warp-lang): {INSTALL}"
        ) from exc
    return warp, mujoco_warp


@dataclass(frozen=True)
class WarpRun:
    """What came back from the device for B worlds.

    ``acc`` (B, ACC_SIZE) the running values (warp_kernels' column names), ``cycles`` (B,) the
    control cycles each world recorded, ``stop_reason`` why a world stopped early ("" if not),
    ``time_s`` the robot time after each cycle (K,), ``dt_s`` the control period, and
    ``overflowed`` (B,) worlds that ran out of contact or constraint slots (their physics is
    not trustworthy; they score as diverged).
    """

    acc: FloatArray
    cycles: np.ndarray
    stop_reason: tuple[str, ...]
    time_s: FloatArray
    dt_s: float
    overflowed: np.ndarray


class WarpBatch:
    """Runs batches of commands as the worlds of one MuJoCo Warp model of the twin on ``device``.

    ``twin`` gives the model, its start state and the readout layout; ``envelope`` the limits
    the device checks as the CPU engine's ``assess`` does; ``workers`` threads (at most one per
    CPU) tabulate the gaits' targets on the host. Raises ConfigError for a device Warp does not
    have or a model MuJoCo Warp cannot run, MissingDependencyError without the gpu extra.
    """

    def __init__(
        self, twin: TwinBatch, envelope: Envelope, *, device: str = "cpu", workers: int = 1
    ) -> None:
        wp, mjw = require_warp()
        # --workers also sizes a CMA-ES population (a multiple of it): thousands, on a GPU.
        self.workers = max(1, min(workers, os.cpu_count() or 1))
        self._wp, self._mjw = wp, mjw
        self.twin, self.envelope = twin, envelope
        try:
            self.device = wp.get_device(device)
        except (RuntimeError, ValueError) as exc:
            names = ", ".join(str(d.alias) for d in wp.get_devices())
            raise ConfigError("device", device, f"Warp has no such device ({names})") from exc
        from snakebot.tuning import warp_kernels

        self._kernels = warp_kernels
        model, lay = twin.model, twin.layout
        with wp.ScopedDevice(self.device):
            try:
                self._model = mjw.put_model(model)
            except NotImplementedError as exc:
                raise ConfigError("engine", "warp", f"MuJoCo Warp cannot run it: {exc}") from exc
            f64 = wp.float64
            self._qpos_index = wp.array(lay.qpos_index.astype(np.int32), dtype=wp.int32)
            self._dof_index = wp.array(lay.dof_index.astype(np.int32), dtype=wp.int32)
            self._damping = wp.array(model.dof_damping[lay.dof_index], dtype=f64)
            self._lower = wp.array(envelope.lower_rad, dtype=f64)
            self._upper = wp.array(envelope.upper_rad, dtype=f64)
            self._geoms = wp.array(lay.capsules.geoms.astype(np.int32), dtype=wp.int32)
            self._radius = wp.array(lay.capsules.radius_m, dtype=f64)
            self._half = wp.array(lay.capsules.half_length_m, dtype=f64)
            self._limits = wp.array(
                [
                    envelope.rest_com_z_m,
                    envelope.lift_limit_m,
                    envelope.contact_tolerance_m,
                    SATURATION_FRACTION * envelope.torque_limit_nm,
                    MOVING_FRACTION * envelope.no_load_speed_rad_s,
                ],
                dtype=f64,
            )
            qpos0 = twin.initial_state[1 : 1 + model.nq]  # mjSTATE_INTEGRATION: time, qpos, ...
            self._initial_qpos = wp.array(qpos0.astype(np.float32), dtype=float)

    def run(self, commands: BatchCommands, duration_s: float, rate_hz: float) -> WarpRun:
        """Run ``commands.size`` worlds for ``duration_s`` at ``rate_hz`` from the twin's start."""
        wp, mjw, kernels, twin = self._wp, self._mjw, self._kernels, self.twin
        count, joints = commands.size, twin.robot.joint_count
        dt = 1.0 / rate_hz
        steps = twin.twin.steps_for(dt)
        schedule = CycleSchedule(
            rate_hz,
            duration_s,
            twin.robot.safety.ramp_s,
            ramp_out=False,
            timestep_s=float(twin.model.opt.timestep),
        )
        times = schedule.cycle_times(commands.length)
        total = len(times) - 1
        envelope = self.envelope
        window = max(1, round(envelope.stop_after_s * rate_hz))
        chunk = TABLE_CYCLES if commands.open_loop else 1
        gaits = tabled_gaits(commands)
        start = np.tile(
            twin.initial_state[1 : 1 + twin.model.nq][twin.layout.qpos_index], (count, 1)
        )
        measured = start.copy()
        commands.reset(measured, schedule)
        with wp.ScopedDevice(self.device):
            data = self._data(count)
            acc = np.zeros((count, kernels.ACC_SIZE))
            acc[:, kernels.COM_X : kernels.COM_Z + 1] = twin.start_com_m
            acc[:, kernels.LAST_YAW_RAD] = head_yaw_rad(twin.start_head_quat)
            acc[:, kernels.MIN_CLEARANCE_M] = math.inf
            acc_d = wp.array(acc, dtype=wp.float64)
            joint_d = wp.zeros((count, joints, kernels.JOINT_SIZE), dtype=wp.float64)
            stop_d = wp.zeros(count, dtype=wp.int32)
            cycles_d = wp.zeros(count, dtype=wp.int32)
            target_d = wp.zeros((count, chunk, joints), dtype=float)
            command_d = wp.zeros((count, chunk, joints), dtype=float)
            timestep = float(twin.model.opt.timestep)
            work = [data.qvel, data.actuator_force, self._dof_index, self._damping, timestep]
            work += [stop_d, acc_d]
            physics = _Physics(wp, mjw, self._model, data, steps, self.device.is_cuda)
            physics.after_step = (kernels.step_work, count, work)
            span = range(0, min(chunk, total))
            rows = self.command_rows(commands, gaits, span, times, measured)
            while span:
                target_d.assign(_padded(rows[0], chunk))
                command_d.assign(_padded(rows[1], chunk))
                for slot, c in enumerate(span):
                    wp.launch(kernels.set_ctrl, (count, joints), [command_d, slot, data.ctrl])
                    physics.step()
                    check = int((c + 1) % window == 0)
                    state = [stop_d, cycles_d, acc_d, joint_d]
                    self.accumulate(data, c, check, window, target_d, command_d, slot, state)
                if not commands.open_loop:
                    measured = data.qpos.numpy()[:, twin.layout.qpos_index].astype(float)
                span = range(span.stop, min(span.stop + chunk, total))
                if span:
                    # Launches return at once on a CUDA device: the host makes the next chunk's
                    # commands while the device runs this one.
                    rows = self.command_rows(commands, gaits, span, times, measured)
                    if stop_d.numpy().all():
                        break
            stops = stop_d.numpy()
            overflowed = data.overflow.numpy() != 0
            reasons = tuple(
                "diverged" if bad else STOP_REASONS[int(s)]
                for s, bad in zip(stops, overflowed, strict=True)
            )
            return WarpRun(
                acc=acc_d.numpy(),
                cycles=cycles_d.numpy().astype(int),
                stop_reason=reasons,
                time_s=np.asarray(times[1:], dtype=float),
                dt_s=dt,
                overflowed=overflowed,
            )

    def accumulate(
        self,
        data: Any,
        cycle: int,
        check: int,
        window: int,
        target: Any,
        command: Any,
        slot: int,
        state: list[Any],
    ) -> None:
        """Launch warp_kernels.accumulate for control cycle ``cycle`` (``slot`` of the chunk
        arrays ``target`` and ``command``, (B, C, N)) of every world. ``data`` is MuJoCo Warp's
        Data or anything with the same arrays; ``state`` the kernel's stop (B,), cycles (B,),
        running values (B, ACC_SIZE) and per-joint values (B, N, JOINT_SIZE)."""
        envelope = self.envelope
        inputs = [
            cycle,
            check,
            window,
            data.qpos,
            data.qvel,
            data.actuator_force,
            data.subtree_com,
            data.xquat,
            data.geom_xpos,
            data.geom_xmat,
            data.qacc_warmstart,
            target,
            command,
            slot,
            self._qpos_index,
            self._dof_index,
            self._lower,
            self._upper,
            self._geoms,
            self._radius,
            self._half,
            self.twin.layout.head_id,
            self._limits,
            int(envelope.allow_roll),
            self._initial_qpos,
            *state,
        ]
        self._wp.launch(self._kernels.accumulate, data.nworld, inputs)

    def command_rows(
        self,
        commands: BatchCommands,
        gaits: Sequence[Gait] | None,
        span: range,
        times: Sequence[float],
        measured: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """Targets and commands (B, C, N) of the cycles in ``span``: from ``commands`` cycle by
        cycle, or with ``gaits`` each gait's targets of all C cycles in one call."""
        clock = [times[c] - times[0] for c in span]
        if gaits is None or not isinstance(commands, GaitCommands):
            rows = [commands(c, t, measured) for c, t in zip(span, clock, strict=True)]
            return np.stack([r[0] for r in rows], axis=1), np.stack([r[1] for r in rows], axis=1)
        at = np.array(clock)
        if self.workers > 1:
            with ThreadPoolExecutor(self.workers) as pool:
                tables = list(pool.map(lambda gait: gait.targets(at), gaits))
        else:
            tables = [gait.targets(at) for gait in gaits]
        targets = np.stack(tables)
        pairs = enumerate(zip(span, clock, strict=True))
        sent = [commands.send(c, t, targets[:, i]) for i, (c, t) in pairs]
        return targets, np.stack(sent, axis=1)

    def _data(self, count: int) -> Any:
        """B copies of the twin's start state on the device."""
        model = self.twin.model
        contacts, rows = capacity(model)
        start = mujoco.MjData(model)
        mujoco.mj_setState(model, start, self.twin.initial_state, _STATE)
        mujoco.mj_forward(model, start)
        return self._mjw.put_data(
            model,
            start,
            nworld=count,
            nconmax=contacts,
            njmax=rows,
        )


class _Physics:
    """One control period of physics steps, each followed by ``after_step``; on a CUDA device a
    captured graph after the first period (the first runs plainly so every kernel is loaded
    before the capture)."""

    def __init__(self, wp: Any, mjw: Any, model: Any, data: Any, steps: int, cuda: bool) -> None:
        self._wp, self._mjw, self._model, self._data = wp, mjw, model, data
        self._steps, self._cuda = steps, cuda
        self._graph: Any = None
        self._periods = 0
        self.after_step: tuple[Any, int, list[Any]] | None = None
        """(kernel, dim, inputs) launched after every physics step (the work integral)."""

    def step(self) -> None:
        """Advance every world by one control period."""
        wp = self._wp
        if self._graph is not None:
            wp.capture_launch(self._graph)
            return
        if self._cuda and self._periods > 0:
            with wp.ScopedCapture() as capture:
                self._period()
            self._graph = capture.graph
            wp.capture_launch(self._graph)
            return
        self._period()
        self._periods += 1

    def _period(self) -> None:
        for _ in range(self._steps):
            self._mjw.step(self._model, self._data)
            if self.after_step is not None:
                kernel, dim, inputs = self.after_step
                self._wp.launch(kernel, dim, inputs)


def capacity(model: mujoco.MjModel) -> tuple[int, int]:
    """Contact slots and constraint rows per world for a twin model: three contacts per geom
    (a capsule lying on the floor touches it at both ends, plus room for self-contacts), each
    contact's rows for its condim and cone, two rows per joint (limits), rows rounded up to 32.
    A world that needs more overflows and scores as diverged (WarpRun.overflowed)."""
    contacts = 3 * int(model.ngeom)
    condim = int(model.geom_condim.max(initial=3))
    elliptic = model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    per_contact = condim if elliptic else max(2 * (condim - 1), 1)
    rows = contacts * per_contact + 2 * int(model.njnt)
    return contacts, -(-rows // 32) * 32


def tabled_gaits(commands: BatchCommands) -> list[Gait] | None:
    """The gaits of ``commands`` when each is a function of time alone (its targets of many
    cycles come from one Gait.targets call), else None."""
    if not isinstance(commands, GaitCommands):
        return None
    gaits = commands.gaits
    return gaits if all(type(g).command is Gait.command for g in gaits) else None


def _padded(block: FloatArray, chunk: int) -> np.ndarray:
    """A chunk's (B, C, N) values as a (B, chunk, N) float32 array, zeros past C."""
    if block.shape[1] < chunk:
        pad = np.zeros((block.shape[0], chunk - block.shape[1], block.shape[2]))
        block = np.concatenate([block, pad], axis=1)
    return block.astype(np.float32)


class WarpGaitProblem(GaitProblem):
    """A GaitProblem whose candidates run as the worlds of one MuJoCo Warp model on
    ``plan.device`` (EvalPlan.engine "warp"); everything else is GaitProblem's."""

    @staticmethod
    def _check_plan(plan: EvalPlan) -> None:
        """ConfigError for a scale-friction model or a Ray executor, before anything is built."""
        if plan.friction_model is not None:
            raise ConfigError(
                "friction_model",
                str(plan.friction_model),
                "runs as a MuJoCo callback on the CPU; the warp engine has plain MuJoCo contacts",
            )
        if plan.executor != "local":
            raise ConfigError(
                "executor",
                plan.executor,
                "the warp engine batches a generation on this machine's device; use local",
            )

    def _start_engine(self) -> None:
        """The batched Warp model on ``plan.device``."""
        self._warp = WarpBatch(
            self._twin, self.envelope, device=self.plan.device, workers=self.plan.workers
        )

    def outcomes(
        self, params: Sequence[Mapping[str, ParamValue]]
    ) -> list[tuple[dict[str, object], Violations]]:
        """Every parameter set's summary and violations, measured on the device in one batch."""
        gaits = [self.gait(p) for p in params]
        run = self._warp.run(
            GaitCommands(gaits, self.robot), self.plan.duration_s, self.plan.rate_hz
        )
        periods = [g.period_s for g in gaits]
        start = self._twin.start_com_m
        return outcomes(run, self.robot, self.envelope, self.plan.duration_s, periods, start)
