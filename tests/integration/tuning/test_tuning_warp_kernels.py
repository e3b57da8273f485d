"""The Warp engine's kernels, fed the CPU engine's own samples, score them as the CPU engine
does: the same summary (RunMetrics), the same violations (assess), the same early stops, and
the same positive work per physics step (readouts.step_work_j).

The physics is left out on purpose (the two engines' physics differ; that tolerance is
test_tuning_engine_warp's): each cycle of a CPU trace is written into arrays laid out as MuJoCo
Warp's Data and run through ``WarpBatch.accumulate`` on Warp's CPU device, so any difference is
in the formulas. Run with ``-m warp``; skipped without the gpu extra.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from snakebot.config import load_robot
from snakebot.tuning.objectives import objective_for
from snakebot.tuning.problem import EvalPlan, GaitProblem
from snakebot.tuning.space import build_space, tuning_base
from snakebot.tuning.trace import Trace, summarise

pytestmark = pytest.mark.warp

DURATION_S = 2.0
# Sidewinding points on snake12: two roll over (stopped as flipped at 1.5 s), one plays, one
# asks for joint speeds beyond the safety layer's (infeasible, runs to the end).
POINTS = [
    (0.144, 1.034, 1.367, 16.584, -0.176),
    (0.223, 0.605, 1.416, 8.257, 0.562),
    (0.572, 0.204, 0.693, 4.233, -1.493),
    (0.639, 1.143, 0.312, 17.907, -1.182),
]


def replay(problem: GaitProblem, traces: list[Trace]) -> Any:
    """The traces' samples through the metrics kernel, cycle by cycle: a WarpRun."""
    import warp as wp

    from snakebot.control.metrics import head_yaw_rad
    from snakebot.tuning import warp_kernels as k
    from snakebot.tuning.engine_warp import STOP_REASONS, WarpBatch, WarpRun

    twin = problem._twin
    batch = WarpBatch(twin, problem.envelope, device="cpu")
    model, lay = twin.model, twin.layout
    count, joints, cycles = len(traces), problem.robot.joint_count, max(t.cycles for t in traces)
    acc = np.zeros((count, k.ACC_SIZE))
    acc[:, k.COM_X : k.COM_Z + 1] = twin.start_com_m
    acc[:, k.LAST_YAW_RAD] = head_yaw_rad(twin.start_head_quat)
    acc[:, k.MIN_CLEARANCE_M] = np.inf
    with wp.ScopedDevice("cpu"):
        state = [
            wp.zeros(count, dtype=wp.int32),
            wp.zeros(count, dtype=wp.int32),
            wp.array(acc, dtype=wp.float64),
            wp.zeros((count, joints, k.JOINT_SIZE), dtype=wp.float64),
        ]
        window = round(problem.envelope.stop_after_s * problem.plan.rate_hz)
        for c in range(cycles):
            at = [min(c, t.cycles - 1) for t in traces]
            qpos = np.zeros((count, model.nq))
            qvel = np.zeros((count, model.nv))
            com = np.zeros((count, model.nbody, 3))
            quat = np.zeros((count, model.nbody, 4))
            geom_z = np.full((count, model.ngeom, 3), 10.0)
            for b, (trace, i) in enumerate(zip(traces, at, strict=True)):
                qpos[b, lay.qpos_index] = trace.position_rad[i]
                qvel[b, lay.dof_index] = trace.velocity_rad_s[i]
                com[b, lay.head_id] = trace.com_m[i]
                quat[b, lay.head_id] = trace.head_quat[i]
                # Lying flat (xmat zero: no axis along z), capsule 0's lowest point is its
                # centre less its radius: the trace's clearance.
                geom_z[b, lay.capsules.geoms[0], 2] = (
                    trace.clearance_m[i] + lay.capsules.radius_m[0]
                )
            force = np.stack([t.actuator_force_nm[i] for t, i in zip(traces, at, strict=True)])
            data = SimpleNamespace(
                nworld=count,
                qpos=wp.array(qpos, dtype=float),
                qvel=wp.array(qvel, dtype=float),
                actuator_force=wp.array(force, dtype=float),
                subtree_com=wp.array(com, dtype=wp.vec3),
                xquat=wp.array(quat, dtype=wp.quat),
                geom_xpos=wp.array(geom_z, dtype=wp.vec3),
                geom_xmat=wp.zeros((count, model.ngeom), dtype=wp.mat33),
                qacc_warmstart=wp.zeros((count, model.nv), dtype=float),
            )
            rows = [
                np.stack([getattr(t, name)[i] for t, i in zip(traces, at, strict=True)])[:, None]
                for name in ("target_rad", "command_rad")
            ]
            target, command = (wp.array(r, dtype=float) for r in rows)
            # The physics steps' work, as step_work adds it for the worlds still running.
            live = state[0].numpy() == 0
            values = state[2].numpy()
            work = np.stack([t.positive_work_j[i].sum() for t, i in zip(traces, at, strict=True)])
            values[live, k.POSITIVE_WORK_J] += work[live]
            state[2].assign(values)
            check = int((c + 1) % window == 0)
            batch.accumulate(data, c, check, window, target, command, 0, state)
        return WarpRun(
            acc=state[2].numpy(),
            cycles=state[1].numpy().astype(int),
            stop_reason=tuple(STOP_REASONS[int(s)] for s in state[0].numpy()),
            time_s=max(traces, key=lambda t: t.cycles).time_s,
            dt_s=traces[0].dt_s,
            overflowed=np.zeros(count, dtype=bool),
        )


def test_the_kernel_scores_the_cpu_engine_samples_as_the_cpu_engine_does() -> None:
    pytest.importorskip("mujoco_warp")
    from snakebot.tuning.feasibility import assess
    from snakebot.tuning.warp_scores import outcomes

    robot = load_robot("snake12")
    limit = float(min(-robot.lower_rad.max(), robot.upper_rad.min()))
    space = build_space("sidewinding", tuning_base("sidewinding", 12, {}), None, {}, limit)
    objective = objective_for("speed", 0.0, robot.body_length_m)
    problem = GaitProblem(robot, space, objective, EvalPlan(duration_s=DURATION_S))
    params = [space.params(x) for x in POINTS]
    traces = problem.run(params)
    assert [t.stop_reason for t in traces] == ["flipped", "flipped", "", ""]
    gaits = [problem.gait(p) for p in params]
    run = replay(problem, traces)
    assert run.cycles.tolist() == [t.cycles for t in traces] == [150, 150, 200, 200]
    assert run.stop_reason == ("flipped", "flipped", "", "")
    scored = outcomes(
        run,
        robot,
        problem.envelope,
        DURATION_S,
        [g.period_s for g in gaits],
        problem._twin.start_com_m,
    )
    assert [v.feasible for _, v in scored] == [False, False, True, False]
    for trace, gait, (summary, violations) in zip(traces, gaits, scored, strict=True):
        expected = summarise(trace, robot, gait.period_s)
        assert summary.keys() == expected.keys()
        for key, value in expected.items():
            if isinstance(value, float):
                assert summary[key] == pytest.approx(value, rel=1e-4, abs=1e-6), key
            elif key == "displacement_m":
                assert summary[key] == pytest.approx(value, abs=1e-6)
            else:
                assert summary[key] == value, key
        cpu = assess(trace, problem.envelope, DURATION_S)
        assert violations.stopped == cpu.stopped
        assert violations.feasible == cpu.feasible
        for key, value in cpu.as_dict().items():
            if isinstance(value, float):
                assert getattr(violations, key) == pytest.approx(value, rel=1e-4, abs=1e-6), key


def test_the_step_work_kernel_is_the_twins_step_work() -> None:
    pytest.importorskip("mujoco_warp")
    import warp as wp

    from snakebot.backends.twin.readouts import step_work_j
    from snakebot.tuning import warp_kernels as k

    rng = np.random.default_rng(3)
    worlds, steps, joints, nv = 3, 5, 4, 10
    dof_index = np.array([6, 7, 8, 9])
    damping = rng.uniform(0.0, 0.5, joints)
    force = rng.normal(0.0, 1.0, (worlds, steps, joints))
    qvel = rng.normal(0.0, 2.0, (worlds, steps, nv))
    expected = step_work_j(force, damping, qvel[..., dof_index], 0.002).sum(axis=-1)
    with wp.ScopedDevice("cpu"):
        stop = wp.array([0, 0, k.FLIPPED], dtype=wp.int32)
        acc = wp.zeros((worlds, k.ACC_SIZE), dtype=wp.float64)
        index = wp.array(dof_index.astype(np.int32), dtype=wp.int32)
        damp = wp.array(damping, dtype=wp.float64)
        for s in range(steps):
            inputs = [
                wp.array(qvel[:, s], dtype=float),
                wp.array(force[:, s], dtype=float),
                index,
                damp,
                0.002,
                stop,
                acc,
            ]
            wp.launch(k.step_work, worlds, inputs)
        work = acc.numpy()[:, k.POSITIVE_WORK_J]
    assert work[:2] == pytest.approx(expected[:2], rel=1e-5)
    assert work[2] == 0.0  # a stopped world adds nothing
