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
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from snakebot.config.schema import RobotConfig
from snakebot.control.cycle import CycleSchedule
from snakebot.control.metrics import GRAVITY_M_S2, head_yaw_rad
from snakebot.errors import ConfigError, MissingDependencyError
from snakebot.gaits.spec import ParamValue
from snakebot.tuning.commands import BatchCommands, GaitCommands
from snakebot.tuning.engine import TwinBatch
from snakebot.tuning.feasibility import (
    FLIPPED_UP_Z,
    MAX_CHATTER,
    MAX_PENETRATION_FRACTION,
    MAX_UPSIDE_DOWN_FRACTION,
    MOVING_FRACTION,
    SATURATION_FRACTION,
    Envelope,
    Violations,
)
from snakebot.tuning.problem import GaitProblem
from snakebot.tuning.trace import FloatArray

INSTALL = "pip install 'snakebot[gpu]'"
DEVICES = ("cpu", "cuda")
CONTACTS_PER_WORLD = 64
CONSTRAINTS_PER_WORLD = 256
_STATE = mujoco.mjtState.mjSTATE_INTEGRATION
_STOPS = ("", "airborne", "flipped", "diverged")

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
            f"--engine warp needs MuJoCo Warp (mujoco-warp, warp-lang): {INSTALL}"
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
    the device checks as the CPU engine's ``assess`` does. Raises ConfigError for a device Warp
    does not have or a model MuJoCo Warp cannot run, MissingDependencyError without the extra.
    """

    def __init__(self, twin: TwinBatch, envelope: Envelope, *, device: str = "cpu") -> None:
        wp, mjw = require_warp()
        self._wp, self._mjw = wp, mjw
        self.twin, self.envelope = twin, envelope
        try:
            self.device = wp.get_device(device)
        except (RuntimeError, ValueError) as exc:
            names = ", ".join(str(d.alias) for d in wp.get_devices())
            raise ConfigError("--device", device, f"Warp has no such device ({names})") from exc
        from snakebot.tuning import warp_kernels

        self._kernels = warp_kernels
        model, lay = twin.model, twin.layout
        with wp.ScopedDevice(self.device):
            try:
                self._model = mjw.put_model(model)
            except NotImplementedError as exc:
                raise ConfigError("--engine", "warp", f"MuJoCo Warp cannot run it: {exc}") from exc
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
        chunk = window if commands.open_loop else 1
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
            physics = _Physics(wp, mjw, self._model, data, steps, self.device.is_cuda)
            k = 0
            while k < total:
                span = range(k, min(k + chunk, total))
                rows = [commands(c, times[c] - times[0], measured) for c in span]
                target_d.assign(_padded([r[0] for r in rows], chunk))
                command_d.assign(_padded([r[1] for r in rows], chunk))
                for slot, c in enumerate(span):
                    wp.launch(kernels.set_ctrl, (count, joints), [command_d, slot, data.ctrl])
                    physics.step()
                    check = int((c + 1) % window == 0)
                    wp.launch(
                        kernels.accumulate,
                        count,
                        [
                            c,
                            dt,
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
                            target_d,
                            command_d,
                            slot,
                            self._qpos_index,
                            self._dof_index,
                            self._damping,
                            self._lower,
                            self._upper,
                            self._geoms,
                            self._radius,
                            self._half,
                            twin.layout.head_id,
                            self._limits,
                            int(envelope.allow_roll),
                            self._initial_qpos,
                            stop_d,
                            cycles_d,
                            acc_d,
                            joint_d,
                        ],
                    )
                k = span.stop
                if not commands.open_loop:
                    measured = data.qpos.numpy()[:, twin.layout.qpos_index].astype(float)
                if k < total and stop_d.numpy().all():
                    break
            stops = stop_d.numpy()
            overflowed = data.overflow.numpy() != 0
            reasons = tuple(
                "diverged" if bad else _STOPS[int(s)]
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

    def _data(self, count: int) -> Any:
        """B copies of the twin's start state on the device."""
        model = self.twin.model
        start = mujoco.MjData(model)
        mujoco.mj_setState(model, start, self.twin.initial_state, _STATE)
        mujoco.mj_forward(model, start)
        return self._mjw.put_data(
            model,
            start,
            nworld=count,
            nconmax=CONTACTS_PER_WORLD,
            njmax=CONSTRAINTS_PER_WORLD,
        )


class _Physics:
    """One control period of physics steps; on a CUDA device a captured graph after the first
    period (the first runs plainly so every kernel is loaded before the capture)."""

    def __init__(self, wp: Any, mjw: Any, model: Any, data: Any, steps: int, cuda: bool) -> None:
        self._wp, self._mjw, self._model, self._data = wp, mjw, model, data
        self._steps, self._cuda = steps, cuda
        self._graph: Any = None
        self._periods = 0

    def step(self) -> None:
        """Advance every world by one control period."""
        wp, mjw = self._wp, self._mjw
        if self._graph is not None:
            wp.capture_launch(self._graph)
            return
        if self._cuda and self._periods > 0:
            with wp.ScopedCapture() as capture:
                for _ in range(self._steps):
                    mjw.step(self._model, self._data)
            self._graph = capture.graph
            wp.capture_launch(self._graph)
            return
        for _ in range(self._steps):
            mjw.step(self._model, self._data)
        self._periods += 1


def _padded(rows: Sequence[FloatArray], chunk: int) -> np.ndarray:
    """Rows (B, N) of the cycles in a chunk as a (B, chunk, N) float32 array, zeros past the end."""
    block = np.stack(rows, axis=1)
    if block.shape[1] < chunk:
        pad = np.zeros((block.shape[0], chunk - block.shape[1], block.shape[2]))
        block = np.concatenate([block, pad], axis=1)
    return block.astype(np.float32)


def outcomes(
    run: WarpRun,
    robot: RobotConfig,
    envelope: Envelope,
    duration_s: float,
    periods_s: Sequence[float | None],
    start_com_m: FloatArray,
) -> list[tuple[dict[str, object], Violations]]:
    """Each world's run summary (the keys and formulas of RunMetrics.summary) and violations
    (those of feasibility.assess), from the device's running values."""
    from snakebot.tuning import warp_kernels as k

    out = []
    joints, dt = robot.joint_count, run.dt_s
    for b, period in enumerate(periods_s):
        a, cycles = run.acc[b], int(run.cycles[b])
        duration = round(float(run.time_s[cycles - 1]), 6) if cycles else 0.0
        gait_cycles = round(duration / period, 6) if period else None
        work = float(a[k.POSITIVE_WORK_J])
        dx = float(a[k.COM_X] - start_com_m[0])
        dy = float(a[k.COM_Y] - start_com_m[1])
        distance = math.hypot(dx, dy)
        summary: dict[str, object] = {
            "duration_s": duration,
            "joints": joints,
            "body_length_m": robot.body_length_m,
            "control_cycles": cycles,
            "cycles": gait_cycles,
            "tracking_rms_rad": math.sqrt(float(a[k.SQUARED_ERROR]) / max(cycles * joints, 1)),
            "max_abs_command_rad": float(a[k.MAX_ABS_COMMAND]),
            "positive_work_j": work,
            "distance_m": distance,
            "displacement_m": [dx, dy],
            "speed_mps": distance / duration if duration > 0 else 0.0,
            "turn_deg": math.degrees(float(a[k.TURN_RAD])),
            "heading_deg": math.degrees(math.atan2(dy, dx)) if distance > 0 else 0.0,
            "body_lengths_per_cycle": (distance / robot.body_length_m / gait_cycles)
            if gait_cycles
            else None,
            "cost_of_transport": (work / (robot.total_mass_kg * GRAVITY_M_S2 * distance))
            if distance > 1e-9
            else None,
        }
        out.append((summary, _violations(a, cycles, dt, envelope, duration_s, run.stop_reason[b])))
    return out


def _violations(
    a: FloatArray, cycles: int, dt: float, envelope: Envelope, duration_s: float, stopped: str
) -> Violations:
    from snakebot.tuning import warp_kernels as k

    speed = max(
        float(a[k.MAX_TARGET_STEP_RAD]) / dt / envelope.max_speed_rad_s - 1.0,
        float(a[k.MAX_SPEED_RAD_S]) / envelope.no_load_speed_rad_s - 1.0,
        0.0,
    )
    planned = max(round(duration_s / dt), cycles, 1)
    longest_s = float(a[k.LONGEST_SATURATION]) * dt
    upside_down = float(a[k.UPSIDE_DOWN_CYCLES]) / cycles if cycles else 0.0
    excess = 0.0 if envelope.allow_roll else upside_down - MAX_UPSIDE_DOWN_FRACTION
    reversals = float(a[k.MAX_REVERSALS]) / cycles if cycles >= 2 else 0.0
    penetration = 0.0
    if envelope.radius_m > 0 and cycles:
        penetration = -float(a[k.MIN_CLEARANCE_M]) / envelope.radius_m - MAX_PENETRATION_FRACTION
    return Violations(
        joint_limit_rad=max(float(a[k.BEYOND_LIMIT_RAD]), 0.0),
        speed_excess=speed,
        saturation_excess_s=max(longest_s - envelope.max_saturation_s, 0.0),
        airborne_fraction=(float(a[k.AIRBORNE_CYCLES]) + planned - cycles) / planned,
        stopped=stopped,
        upside_down_fraction=upside_down,
        upside_down_excess=max(excess, 0.0),
        penetration_excess=max(penetration, 0.0),
        chatter_excess=max(reversals - MAX_CHATTER, 0.0),
    )


class WarpGaitProblem(GaitProblem):
    """A GaitProblem whose candidates run as the worlds of one MuJoCo Warp model on
    ``plan.device`` (EvalPlan.engine "warp"); everything else is GaitProblem's."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        if self.plan.friction_model is not None:
            raise ConfigError(
                "--friction-model",
                str(self.plan.friction_model),
                "runs as a MuJoCo callback on the CPU; --engine warp has plain MuJoCo contacts",
            )
        self._warp = WarpBatch(self._twin, self.envelope, device=self.plan.device)

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
