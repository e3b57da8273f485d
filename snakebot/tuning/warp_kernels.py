"""The Warp kernels of the MuJoCo Warp engine: commands in, the run's metrics accumulated per world.

One thread per world. ``accumulate`` reads what the CPU engine samples every control cycle
(snakebot.tuning.engine.TwinBatch) and ``step_work`` the positive work of every physics step
(readouts.step_work_j), and both fold it into running sums and extremes, so a run's
summary (snakebot.control.metrics.RunMetrics) and its violations
(snakebot.tuning.feasibility.assess) come out of a few numbers per world, never a trace.
Sums are float64: a run of 10^3 cycles adds 10^4 small terms.

Imported only by snakebot.tuning.engine_warp, once ``warp`` is known to be installed.
"""

from __future__ import annotations

import warp as wp

# Per-world running values, columns of the (B, ACC_SIZE) float64 array.
SQUARED_ERROR = 0
MAX_ABS_COMMAND = 1
POSITIVE_WORK_J = 2
TURN_RAD = 3
LAST_YAW_RAD = 4
COM_X = 5
COM_Y = 6
COM_Z = 7
BEYOND_LIMIT_RAD = 8
MAX_TARGET_STEP_RAD = 9
MAX_SPEED_RAD_S = 10
LONGEST_SATURATION = 11
AIRBORNE_CYCLES = 12
UPSIDE_DOWN_CYCLES = 13
MIN_CLEARANCE_M = 14
MAX_REVERSALS = 15
AIRBORNE_RUN = 16
FLIPPED_RUN = 17
ACC_SIZE = 18

# Per-joint running values, the last axis of the (B, N, JOINT_SIZE) float64 array.
PREVIOUS_TARGET = 0
PREVIOUS_SIGN = 1
SATURATION_RUN = 2
REVERSALS = 3
JOINT_SIZE = 4

# Why a world stopped (the (B,) int32 ``stop`` array); 0 while it runs.
RUNNING = 0
AIRBORNE = 1
FLIPPED = 2
DIVERGED = 3

# MuJoCo's mjMAXVAL: mj_checkPos / mj_checkVel call a larger value unstable and reset the data.
MAX_VALUE = 1.0e10

_TWO_PI = wp.constant(wp.float64(6.283185307179586))
_MAX_VALUE = wp.constant(MAX_VALUE)


@wp.kernel
def set_ctrl(command: wp.array3d[float], slot: int, ctrl: wp.array2d[float]):
    """ctrl[w, j] = command[w, slot, j]: one cycle's commands (the chunk's row ``slot``)."""
    w, j = wp.tid()
    ctrl[w, j] = command[w, slot, j]


@wp.func
def _head_yaw(q: wp.quat) -> wp.float64:
    # MuJoCo Warp keeps MuJoCo's (w, x, y, z) order in its quaternions.
    w = wp.float64(q[0])
    x = wp.float64(q[1])
    y = wp.float64(q[2])
    z = wp.float64(q[3])
    two = wp.float64(2.0)
    return wp.atan2(two * (w * z + x * y), wp.float64(1.0) - two * (y * y + z * z))


@wp.func
def _remainder(a: wp.float64, b: wp.float64) -> wp.float64:
    return a - b * wp.round(a / b)


@wp.kernel
def step_work(
    qvel: wp.array2d[float],
    actuator_force: wp.array2d[float],
    dof_index: wp.array[int],
    damping: wp.array[wp.float64],
    timestep_s: wp.float64,
    stop: wp.array[int],
    acc: wp.array2d[wp.float64],
):
    """After each physics step: add each live world's positive joint work in the step,
    sum over joints of max((drive - damping * velocity) * velocity, 0) * timestep (the twin's
    readouts.step_work_j, the velocity after the step)."""
    w = wp.tid()
    if stop[w] != 0:
        return
    work = wp.float64(0.0)
    for j in range(dof_index.shape[0]):
        velocity = wp.float64(qvel[w, dof_index[j]])
        power = (wp.float64(actuator_force[w, j]) - damping[j] * velocity) * velocity
        if power > wp.float64(0.0):
            work += power
    acc[w, POSITIVE_WORK_J] = acc[w, POSITIVE_WORK_J] + work * timestep_s


@wp.kernel
def accumulate(
    cycle: int,
    check: int,
    window: int,
    qpos: wp.array2d[float],
    qvel: wp.array2d[float],
    actuator_force: wp.array2d[float],
    subtree_com: wp.array2d[wp.vec3],
    xquat: wp.array2d[wp.quat],
    geom_xpos: wp.array2d[wp.vec3],
    geom_xmat: wp.array2d[wp.mat33],
    qacc_warmstart: wp.array2d[float],
    target: wp.array3d[float],
    command: wp.array3d[float],
    slot: int,
    qpos_index: wp.array[int],
    dof_index: wp.array[int],
    lower_rad: wp.array[wp.float64],
    upper_rad: wp.array[wp.float64],
    capsule_geoms: wp.array[int],
    capsule_radius: wp.array[wp.float64],
    capsule_half_length: wp.array[wp.float64],
    head: int,
    limits: wp.array[wp.float64],
    allow_roll: int,
    initial_qpos: wp.array[float],
    stop: wp.array[int],
    cycles: wp.array[int],
    acc: wp.array2d[wp.float64],
    joint: wp.array3d[wp.float64],
):
    """Fold control cycle ``cycle`` (0-based, ``slot`` in the uploaded chunk) into each live
    world's running values (the positive work is step_work's, every physics step); stop worlds
    that diverged or, on a ``check`` cycle, spent the last ``window`` cycles airborne or upside
    down.

    ``limits``: rest COM height, lift limit, contact tolerance (m), the saturated torque (N·m),
    the moving speed for chatter (rad/s).
    """
    w = wp.tid()
    if stop[w] != 0:
        return
    nq = qpos.shape[1]
    nv = qvel.shape[1]
    bad = int(0)  # noqa: UP018, RUF046 (Warp: a value a dynamic loop changes)
    for i in range(nq):
        v = qpos[w, i]
        if not wp.isfinite(v) or wp.abs(v) > _MAX_VALUE:
            bad = 1
    for i in range(nv):
        v = qvel[w, i]
        if not wp.isfinite(v) or wp.abs(v) > _MAX_VALUE:
            bad = 1
    if bad != 0:
        # A dead world sits still at its start pose: NaNs would only spread through the shared
        # contact buffers.
        stop[w] = DIVERGED
        for i in range(nq):
            qpos[w, i] = initial_qpos[i]
        for i in range(nv):
            qvel[w, i] = 0.0
            qacc_warmstart[w, i] = 0.0
        return

    rest_z = limits[0]
    lift = limits[1]
    tolerance = limits[2]
    saturated_nm = limits[3]
    moving = limits[4]
    zero = wp.float64(0.0)
    first = cycle == 0
    n = qpos_index.shape[0]
    squared = zero
    for j in range(n):
        position = wp.float64(qpos[w, qpos_index[j]])
        velocity = wp.float64(qvel[w, dof_index[j]])
        force = wp.float64(actuator_force[w, j])
        goal = wp.float64(target[w, slot, j])
        sent = wp.float64(command[w, slot, j])
        error = sent - position
        squared += error * error
        acc[w, MAX_ABS_COMMAND] = wp.max(acc[w, MAX_ABS_COMMAND], wp.abs(sent))
        beyond = wp.max(goal - upper_rad[j], lower_rad[j] - goal)
        acc[w, BEYOND_LIMIT_RAD] = wp.max(acc[w, BEYOND_LIMIT_RAD], beyond)
        if not first:
            step = wp.abs(goal - joint[w, j, PREVIOUS_TARGET])
            acc[w, MAX_TARGET_STEP_RAD] = wp.max(acc[w, MAX_TARGET_STEP_RAD], step)
        joint[w, j, PREVIOUS_TARGET] = goal
        acc[w, MAX_SPEED_RAD_S] = wp.max(acc[w, MAX_SPEED_RAD_S], wp.abs(velocity))
        run = zero
        if wp.abs(force) >= saturated_nm:
            run = joint[w, j, SATURATION_RUN] + wp.float64(1.0)
        joint[w, j, SATURATION_RUN] = run
        acc[w, LONGEST_SATURATION] = wp.max(acc[w, LONGEST_SATURATION], run)
        sign = zero
        if velocity > moving:
            sign = wp.float64(1.0)
        elif velocity < -moving:
            sign = wp.float64(-1.0)
        if sign * joint[w, j, PREVIOUS_SIGN] < zero:
            joint[w, j, REVERSALS] = joint[w, j, REVERSALS] + wp.float64(1.0)
            acc[w, MAX_REVERSALS] = wp.max(acc[w, MAX_REVERSALS], joint[w, j, REVERSALS])
        joint[w, j, PREVIOUS_SIGN] = sign
    acc[w, SQUARED_ERROR] = acc[w, SQUARED_ERROR] + squared

    com = subtree_com[w, head]
    acc[w, COM_X] = wp.float64(com[0])
    acc[w, COM_Y] = wp.float64(com[1])
    acc[w, COM_Z] = wp.float64(com[2])
    quat = xquat[w, head]
    yaw = _head_yaw(quat)
    acc[w, TURN_RAD] = acc[w, TURN_RAD] + _remainder(yaw - acc[w, LAST_YAW_RAD], _TWO_PI)
    acc[w, LAST_YAW_RAD] = yaw

    clearance = wp.float64(1.0e30)
    for c in range(capsule_geoms.shape[0]):
        g = capsule_geoms[c]
        axis_z = wp.abs(wp.float64(geom_xmat[w, g][2, 2]))
        lowest = wp.float64(geom_xpos[w, g][2]) - capsule_radius[c]
        lowest = lowest - capsule_half_length[c] * axis_z
        clearance = wp.min(clearance, lowest)
    acc[w, MIN_CLEARANCE_M] = wp.min(acc[w, MIN_CLEARANCE_M], clearance)

    airborne = clearance > tolerance or wp.float64(com[2]) - rest_z > lift
    qx = wp.float64(quat[1])
    qy = wp.float64(quat[2])
    up_z = wp.float64(1.0) - wp.float64(2.0) * (qx * qx + qy * qy)
    upside_down = up_z < wp.float64(-0.5)
    if airborne:
        acc[w, AIRBORNE_CYCLES] = acc[w, AIRBORNE_CYCLES] + wp.float64(1.0)
        acc[w, AIRBORNE_RUN] = acc[w, AIRBORNE_RUN] + wp.float64(1.0)
    else:
        acc[w, AIRBORNE_RUN] = zero
    if upside_down:
        acc[w, UPSIDE_DOWN_CYCLES] = acc[w, UPSIDE_DOWN_CYCLES] + wp.float64(1.0)
    if upside_down and allow_roll == 0:
        acc[w, FLIPPED_RUN] = acc[w, FLIPPED_RUN] + wp.float64(1.0)
    else:
        acc[w, FLIPPED_RUN] = zero
    cycles[w] = cycle + 1
    if check != 0:
        if acc[w, AIRBORNE_RUN] >= wp.float64(window):
            stop[w] = AIRBORNE
        elif acc[w, FLIPPED_RUN] >= wp.float64(window):
            stop[w] = FLIPPED
