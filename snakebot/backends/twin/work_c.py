"""The twin's physics steps of one control period and their positive work, in C.

Integrating the work in Python means one ``mj_step`` call per physics step plus a few numpy calls
per period: 10-17 % of a snake8 cycle. Here the loop ``mj_step; add max(τ·ω, 0)`` runs in a small
C function called once per period through ctypes, with ``readouts.step_work_j``'s arithmetic in
its order (no fused multiply-add), so the twin, the numpy fallback and the batched engine agree
bit for bit (tests/integration/tuning/test_tuning_engine.py holds them to it). Compiled and
cached as the scale friction is (native_cache.py); without a compiler the twin steps in Python
with a warning.
"""

from __future__ import annotations

import ctypes

import mujoco
import numpy as np

from snakebot.backends import native_cache
from snakebot.backends.native_cache import CompileError

__all__ = ["C_SOURCE", "CompileError", "WorkStepper", "load"]

C_SOURCE = r"""
#if defined(__clang__)
#pragma clang fp contract(off)
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif
#include <mujoco/mujoco.h>

/* `steps` physics steps; after each, joint j's servo torque (actuator force j less the joint
   damping at the joint's speed) times that speed, where positive, is summed into work[j]
   (zeroed by the caller), and the sums are multiplied by the timestep at the end. */
void snakebot_twin_advance(const mjModel* m, mjData* d, int steps, int joints,
                           const long long* dof, double* work) {
  for (int i = 0; i < steps; i++) {
    mj_step(m, d);
    for (int j = 0; j < joints; j++) {
      double speed = d->qvel[dof[j]];
      double power = (d->actuator_force[j] - m->dof_damping[dof[j]] * speed) * speed;
      work[j] += power > 0.0 ? power : 0.0;
    }
  }
  for (int j = 0; j < joints; j++) work[j] *= m->opt.timestep;
}
"""

_LIBRARY: ctypes.CDLL | None = None


def load() -> ctypes.CDLL:
    """The compiled stepping library, compiling it on first use; CompileError if impossible."""
    global _LIBRARY
    if _LIBRARY is None:
        library = native_cache.load_library("twin_work", C_SOURCE)
        library.snakebot_twin_advance.restype = None
        library.snakebot_twin_advance.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
        library.snakebot_twin_advance.argtypes += [ctypes.c_int] * 2 + [ctypes.c_void_p] * 2
        _LIBRARY = library
    return _LIBRARY


class WorkStepper:
    """Steps ``model``/``data`` and integrates the positive work of the joints at ``dof_index``
    (N,) (actuator j drives joint j, as the twin builds them). CompileError if the C cannot be
    built."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, dof_index: np.ndarray) -> None:
        self._function = load().snakebot_twin_advance
        self._dof = np.ascontiguousarray(dof_index, dtype=np.int64)  # lives as long as we do
        self._pointers = (model._address, data._address, self._dof.ctypes.data)
        self._joints = int(self._dof.shape[0])

    def advance(self, steps: int) -> np.ndarray:
        """``steps`` physics steps; each joint's positive work over them (N,) J."""
        model, data, dof = self._pointers
        work = np.zeros(self._joints)
        self._function(model, data, steps, self._joints, dof, work.ctypes.data)
        return work
