"""What the twin reads out of MuJoCo's state: one formula each, for one run or a batch.

The twin backend, its physics-health check, the batched tuning engine (``mujoco.batch``, arrays
(B, ...)) and the learning environments all read these quantities; each formula lives here once,
so a tuned or learned result measured on one path is what another path measures:

- ``servo_torque_nm``: each servo's output torque, the actuator's drive less the joint damping
  (back-EMF and gear friction) at the joint's speed.
- ``positive_power_w``: the mechanical power each joint puts in (negative power, a joint being
  driven, counts nothing). It is every backend's formula (the servo bus reports effort and
  velocity too), so it is defined beside ``JointState`` in ``snakebot.types`` and the twin's
  users take it from here.
- ``step_work_j``: positive work integrated over every physics step of a control period, the
  twin's and the batched engine's one formula (docs/physics.md, "Energy"): sampling the power
  once per period misses what happens between samples (78x too little for a stiff servo).
- ``Capsules.clearance_m``: how high the lowest point of the module capsules is above z = 0.
- ``unstable_count`` / ``StepCheck``: whether MuJoCo met an instability inside a physics step
  (it answers one by resetting the state and counting a warning, not with NaN), and when.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

from snakebot.backends.twin.model_builder import link_name
from snakebot.errors import SimulationDivergedError
from snakebot.types import positive_power_w

__all__ = [
    "UNSTABLE_WARNINGS",
    "WARNING_NUMBER",
    "Capsules",
    "StepCheck",
    "as_slice",
    "diverged_error",
    "divergence_time_s",
    "positive_power_w",
    "servo_torque_nm",
    "step_work_j",
    "unstable_count",
]

FloatArray = npt.NDArray[np.float64]

UNSTABLE_WARNINGS = np.array(
    [
        mujoco.mjtWarning.mjWARN_BADQACC,
        mujoco.mjtWarning.mjWARN_BADQPOS,
        mujoco.mjtWarning.mjWARN_BADQVEL,
    ],
    dtype=int,
)
"""The warnings MuJoCo counts when it resets an unstable simulation."""

WARNING_NUMBER = 1
"""Index of the count in a ``mujoco.batch.Batch.warning`` array (B, nwarn, 2): each warning is
an ``mjWarningStat`` (lastinfo, number). Index 0 is ``lastinfo``, the index of the DOF that
went bad, which stays 0 when DOF 0 (the floating base) is the first to blow up."""


def as_slice(index: npt.NDArray[np.intp]) -> slice | npt.NDArray[np.intp]:
    """``index`` as a slice where it is a run of consecutive addresses (a view, not a copy: a
    per-cycle read through it costs a fraction of a fancy index's), else as it is."""
    if len(index) and np.array_equal(index, np.arange(index[0], index[0] + len(index))):
        return slice(int(index[0]), int(index[0]) + len(index))
    return index


def servo_torque_nm(
    actuator_force_nm: FloatArray, joint_damping_nms: FloatArray, velocity_rad_s: FloatArray
) -> FloatArray:
    """Each servo's output torque in N·m: the drive less the joint's damping at its speed.

    Any leading shape: (N,) for one run, (B, K, N) for a batch's cycles; ``joint_damping_nms``
    broadcasts (MjModel's ``dof_damping`` of the joints, per run where models differ).
    """
    torque: FloatArray = actuator_force_nm - joint_damping_nms * velocity_rad_s
    return torque


def step_work_j(
    actuator_force_nm: FloatArray,
    joint_damping_nms: FloatArray,
    velocity_rad_s: FloatArray,
    timestep_s: float,
) -> FloatArray:
    """Positive work of each joint over S physics steps, J: (..., S, N) in, (..., N) out.

    ``actuator_force_nm`` and ``velocity_rad_s`` are MjData's ``actuator_force`` and the joints'
    ``qvel`` after each step; ``joint_damping_nms`` (..., N) broadcasts over the steps. Each
    step counts ``positive_power_w(servo torque, velocity) * timestep_s``: with the velocity
    after the step, which is the one MuJoCo's semi-implicit integration moves the joint by, the
    product is the work the torque did in that step. The steps add in order, so one period on
    the twin and the same period inside a batch's (B, C, S, N) arrays give the same bits.
    """
    damping = np.expand_dims(joint_damping_nms, -2)
    # positive_power_w(servo_torque_nm(...), velocity) in place: a few numpy calls per period.
    power = servo_torque_nm(actuator_force_nm, damping, velocity_rad_s)
    power *= velocity_rad_s
    np.maximum(power, 0.0, out=power)
    work: FloatArray = power.sum(axis=-2)
    work *= timestep_s
    return work


@dataclass(frozen=True)
class Capsules:
    """The module capsules of a twin model: geom ids (M,), radii and half lengths (M,) in m."""

    geoms: npt.NDArray[np.intp]
    radius_m: FloatArray
    half_length_m: FloatArray

    @classmethod
    def of_modules(cls, model: mujoco.MjModel, link_count: int) -> Capsules:
        """The ``link_count`` module capsules of a twin model built by ``build_model``."""
        geoms = np.array([model.geom(f"{link_name(i)}_geom").id for i in range(link_count)])
        return cls(geoms, model.geom_size[geoms, 0].copy(), model.geom_size[geoms, 1].copy())

    def clearance_m(self, geom_xpos: FloatArray, geom_xmat: FloatArray) -> FloatArray:
        """Height of the lowest capsule point above z = 0 for MjData's ``geom_xpos`` (..., G, 3)
        and ``geom_xmat`` (..., G, 9): shape (...) (a 0-d array for one MjData)."""
        axis_z = np.abs(geom_xmat[..., self.geoms, 8])
        lowest = geom_xpos[..., self.geoms, 2] - self.radius_m - self.half_length_m * axis_z
        clearance: FloatArray = lowest.min(axis=-1)
        return clearance


def unstable_count(warning_number: npt.ArrayLike) -> npt.NDArray[np.int64]:
    """How often MuJoCo has reset an unstable simulation: from ``MjData.warning.number``
    (nwarn,) a 0-d count, from a batch's ``warning[..., WARNING_NUMBER]`` (B, nwarn) one per run."""
    count: npt.NDArray[np.int64] = np.asarray(warning_number)[..., UNSTABLE_WARNINGS].sum(axis=-1)
    return count


def divergence_time_s(
    time_before_s: float, steps: int, timestep_s: float, time_after_s: float
) -> float:
    """When MuJoCo's reset happened inside ``mj_step(..., steps)``.

    MuJoCo answers bad accelerations by resetting the data (time 0) and then stepping on, so the
    clock after the call counts only the steps since the reset: the reset came ``steps`` minus
    those steps after ``time_before_s``.
    """
    after_reset = round(time_after_s / timestep_s)
    return time_before_s + max(steps - after_reset, 0) * timestep_s


def diverged_error(
    time_before_s: float, steps: int, timestep_s: float, time_after_s: float
) -> SimulationDivergedError:
    """The error for an instability MuJoCo met inside ``mj_step(..., steps)`` begun at
    ``time_before_s`` (``divergence_time_s`` says when)."""
    return SimulationDivergedError(
        divergence_time_s(time_before_s, steps, timestep_s, time_after_s),
        "MuJoCo reported bad accelerations (state was reset)",
    )


class StepCheck:
    """The whole-physics-step check of one MjData: did the physics steps since ``start`` meet
    an instability (``unstable_count`` rose) or, with ``finite_positions``, leave a position
    that is not finite? The counters are read through a view of MjData's own, a few scalar
    reads per control cycle."""

    def __init__(
        self, model: mujoco.MjModel, data: mujoco.MjData, *, finite_positions: bool = False
    ) -> None:
        self._model, self._data = model, data
        self._number = data.warning.number  # a view: MuJoCo counts into it
        self._which = tuple(UNSTABLE_WARNINGS.tolist())
        self._finite = finite_positions
        self._before = 0
        self._time_before_s = 0.0

    def count(self) -> int:
        """``unstable_count`` of the data now."""
        number = self._number
        first, second, third = self._which
        return int(number[first] + number[second] + number[third])

    def start(self) -> None:
        """Before stepping: remember the count and the time."""
        self._before = self.count()
        self._time_before_s = float(self._data.time)

    def finish(self, steps: int) -> None:
        """After ``steps`` physics steps: SimulationDivergedError at the time the instability
        happened (MuJoCo reset the state and stepped on), if one did."""
        data = self._data
        diverged = self.count() != self._before
        if diverged or (self._finite and not np.isfinite(data.qpos).all()):
            timestep = float(self._model.opt.timestep)
            raise diverged_error(self._time_before_s, steps, timestep, float(data.time))
