"""Miller's directional rule and the physics steps of one control period, in C.

The numpy rule (friction.py) costs about as much as the mj_step it follows on a 10-segment body,
because every step pays a dozen numpy calls. Here the loop ``mj_step; rule`` runs in a small C
function called once per control period through ctypes, with the same arithmetic in the same
order as DirectionalFriction.apply, so both give the same velocities bit for bit (the tests hold
them to it). It is compiled and cached as the scale friction is (native_cache.py); with no
compiler the backend warns and steps with the numpy rule.
"""

from __future__ import annotations

import ctypes

import mujoco
import numpy as np

from snakebot.backends import native_cache
from snakebot.backends.native_cache import CompileError
from snakebot.backends.softbody.friction import DirectionalFriction

__all__ = ["C_SOURCE", "CompileError", "CompiledStepper", "load"]

C_SOURCE = r"""
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <mujoco/mujoco.h>

/* Copy of the numpy rule's arithmetic: ring sums of 4 corner displacements in order, the spine
   start + 0.25 (ahead - behind), divided by its norm; points touching and moving backward lose
   the backward component. The dot products add x and z first, then y, as numpy's einsum does
   for rows of 3 (its SIMD pairs), so the two agree bit for bit. Returns how many points were
   projected. */
static long rule(const mjModel* m, mjData* d, int points, const int64_t* geom_point,
                 const int64_t* point_ring, const int64_t* ahead, const int64_t* behind,
                 const double* start_spine, unsigned char* touch, double* ring, double* spine,
                 int finite, double impulse_per_n, double* load) {
  int rings = points / 4;
  const double* x = d->qpos;
  double* v = d->qvel;
  long projected = 0;
  memset(touch, 0, points + 1);
  for (int i = 0; i < d->ncon; i++) {
    for (int k = 0; k < 2; k++) {
      int g = d->contact[i].geom[k];
      if (g >= 0 && g < m->ngeom) touch[geom_point[g]] = 1;
    }
  }
  for (int r = 0; r < rings; r++) {
    for (int j = 0; j < 3; j++) {
      const double* c = x + 12 * r + j;
      ring[3 * r + j] = ((c[0] + c[3]) + c[6]) + c[9];
    }
  }
  for (int r = 0; r < rings; r++) {
    double* s = spine + 3 * r;
    for (int j = 0; j < 3; j++)
      s[j] = start_spine[3 * r + j] + 0.25 * (ring[3 * ahead[r] + j] - ring[3 * behind[r] + j]);
    double norm = sqrt((s[0] * s[0] + s[2] * s[2]) + s[1] * s[1]);
    s[0] /= norm; s[1] /= norm; s[2] /= norm;
  }
  if (finite) {
    /* Finite backward friction (friction.py _apply_finite): at most impulse_per_n * load of
       the backward speed off, load the point's normal force summed over its contacts. */
    memset(load, 0, sizeof(double) * (points + 1));
    for (int i = 0; i < d->ncon; i++) {
      int adr = d->contact[i].efc_address;
      if (adr < 0) continue;
      double normal = 0.0;
      for (int k = 0; k < 2 * (d->contact[i].dim - 1); k++) normal += d->efc_force[adr + k];
      for (int k = 0; k < 2; k++) {
        int g = d->contact[i].geom[k];
        if (g >= 0 && g < m->ngeom) load[geom_point[g]] += normal;
      }
    }
  }
  for (int p = 0; p < points; p++) {
    if (!touch[p]) continue;
    const double* s = spine + 3 * point_ring[p];
    double* w = v + 3 * p;
    double along = (w[0] * s[0] + w[2] * s[2]) + w[1] * s[1];
    if (!(along < 0.0)) continue;
    if (finite) {
      double taken = impulse_per_n * load[p];
      if (-along < taken) taken = -along;
      if (!(taken > 0.0)) continue;
      w[0] += s[0] * taken; w[1] += s[1] * taken; w[2] += s[2] * taken;
    } else {
      w[0] -= s[0] * along; w[1] -= s[1] * along; w[2] -= s[2] * along;
    }
    projected++;
  }
  return projected;
}

/* Each joint's positive muscle power over the step just taken, times the timestep, added to
   `work` (joints): its weights on its segment's `width` springs (`columns`) times their
   actuator forces, times the rate weights times their actuator velocities (MuscleMap.
   power_rows), both computed at the start of the step. */
static void add_work(const mjModel* m, const mjData* d, int joints, int width,
                     const int64_t* columns, const double* effort_rows,
                     const double* rate_rows, double* work, double* spring_work) {
  for (int a = 0; a < m->nu; a++) {
    double power = d->actuator_force[a] * d->actuator_velocity[a];
    if (power > 0.0) *spring_work += power * m->opt.timestep;
  }
  for (int j = 0; j < joints; j++) {
    const int64_t* c = columns + (long)j * width;
    const double* e = effort_rows + (long)j * width;
    const double* r = rate_rows + (long)j * width;
    double effort = 0.0, rate = 0.0;
    for (int k = 0; k < width; k++) {
      effort += e[k] * d->actuator_force[c[k]];
      rate += r[k] * d->actuator_velocity[c[k]];
    }
    double power = effort * rate;
    if (power > 0.0) work[j] += power * m->opt.timestep;
  }
}

/* Step `steps` times, the rule after each step that has contacts (when `enabled`); the
   positions (qpos) and the time before the last step are copied to `previous` (3 P + 1);
   each step's positive muscle work is added to `work` (add_work). */
long snakebot_soft_advance(const mjModel* m, mjData* d, int steps, int enabled, int points,
                           const int64_t* geom_point, const int64_t* point_ring,
                           const int64_t* ahead, const int64_t* behind,
                           const double* start_spine, unsigned char* touch,
                           double* ring, double* spine, double* previous, int joints,
                           int width, const int64_t* columns, const double* effort_rows,
                           const double* rate_rows, double* work, int finite,
                           double impulse_per_n, double* load, double* spring_work) {
  long projected = 0;
  for (int i = 0; i < steps; i++) {
    if (i == steps - 1) {
      memcpy(previous, d->qpos, sizeof(double) * 3 * points);
      previous[3 * points] = d->time;
    }
    mj_step(m, d);
    add_work(m, d, joints, width, columns, effort_rows, rate_rows, work, spring_work);
    if (enabled && d->ncon)
      projected += rule(m, d, points, geom_point, point_ring, ahead, behind, start_spine,
                        touch, ring, spine, finite, impulse_per_n, load);
  }
  return projected;
}
"""

_LIBRARY: ctypes.CDLL | None = None


def load() -> ctypes.CDLL:
    """The compiled stepping library, compiling it on first use; CompileError if impossible."""
    global _LIBRARY
    if _LIBRARY is None:
        library = native_cache.load_library("soft_friction", C_SOURCE)
        library.snakebot_soft_advance.restype = ctypes.c_long
        library.snakebot_soft_advance.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
        library.snakebot_soft_advance.argtypes += [ctypes.c_int] * 3 + [ctypes.c_void_p] * 9
        library.snakebot_soft_advance.argtypes += [ctypes.c_int] * 2 + [ctypes.c_void_p] * 4
        library.snakebot_soft_advance.argtypes += [ctypes.c_int, ctypes.c_double]
        library.snakebot_soft_advance.argtypes += [ctypes.c_void_p] * 2
        _LIBRARY = library
    return _LIBRARY


class CompiledStepper:
    """Steps ``model``/``data`` with ``rule``'s directional friction in C.

    ``previous`` (P, 3) holds the point displacements and ``previous_time_s`` the time before
    the last step of the latest ``advance``. The model's qpos and qvel must be the points' slide
    joints, 3 per point in lattice order (as build_body_model makes them). CompileError if the
    C cannot be built.
    """

    def __init__(
        self, model: mujoco.MjModel, data: mujoco.MjData, rule: DirectionalFriction
    ) -> None:
        self._function = load().snakebot_soft_advance
        self.rule = rule
        points = rule.point_ring.shape[0]
        rings = points // 4
        self._previous = np.zeros(3 * points + 1)
        self.previous = self._previous[:-1].reshape(points, 3)
        # The C reads these arrays; they live as long as the stepper (ctypes keeps no reference).
        self._keep = (
            np.ascontiguousarray(rule.geom_point, dtype=np.int64),
            np.ascontiguousarray(rule.point_ring, dtype=np.int64),
            np.ascontiguousarray(rule._ahead, dtype=np.int64),
            np.ascontiguousarray(rule._behind, dtype=np.int64),
            np.ascontiguousarray(rule._start_spine, dtype=np.float64),
            np.zeros(points + 1, dtype=np.uint8),
            np.zeros((rings, 3)),
            np.zeros((rings, 3)),
        )
        self._pointers = [model._address, data._address]
        self._arrays = [a.ctypes.data for a in self._keep] + [self._previous.ctypes.data]
        self._points = points
        self._load = np.zeros(points + 1)

    @property
    def previous_time_s(self) -> float:
        """Simulated time before the last step of the latest ``advance``."""
        return float(self._previous[-1])

    def advance(
        self, steps: int, columns: np.ndarray, effort_rows: np.ndarray, rate_rows: np.ndarray
    ) -> tuple[np.ndarray, float]:
        """``steps`` physics steps, the rule after each (if the rule is enabled); returns each
        joint's positive muscle work over them (N,) J, from ``MuscleMap.power_rows``'s springs
        and weights (N, K) each (the numpy path's ``muscle_work_j``, summed in another order),
        and all springs' positive work, J (``spring_work_j``)."""
        model, data = self._pointers
        springs = np.ascontiguousarray(columns, dtype=np.int64)
        effort = np.ascontiguousarray(effort_rows, dtype=np.float64)
        rate = np.ascontiguousarray(rate_rows, dtype=np.float64)
        work = np.zeros(effort.shape[0])
        spring = np.zeros(1)
        self.rule.projected += self._function(
            model,
            data,
            steps,
            int(self.rule.enabled),
            self._points,
            *self._arrays,
            effort.shape[0],
            effort.shape[1],
            springs.ctypes.data,
            effort.ctypes.data,
            rate.ctypes.data,
            work.ctypes.data,
            int(not self.rule.ideal),
            self.rule._impulse_per_n,
            self._load.ctypes.data,
            spring.ctypes.data,
        )
        return work, float(spring[0])
