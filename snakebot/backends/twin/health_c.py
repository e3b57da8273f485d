"""The physics-health check's per-cycle scan of MjData, in C.

``HealthMonitor.sample`` looks at the contacts (deepest floor and module-module penetration,
whether any module touches the ground), the capsules' lowest point when none does, and the
joints' fastest speed, every control cycle. In Python that is a pass over the contacts plus a
few numpy calls, about a fifth of the controller's own cost on snake8 (docs/benchmarks.md);
here it is one ctypes call with the same comparisons and arithmetic in the same order
(``readouts.Capsules.clearance_m``'s ``z - r - h |R_zz|``, no fused multiply-add), so the
monitor's figures are the Python pass's bit for bit (tests/integration/twin/test_physics_health.py
holds them to it). Compiled and cached as the work stepper is (native_cache.py); without a
compiler the monitor scans in Python.
"""

from __future__ import annotations

import ctypes

import mujoco
import numpy as np

from snakebot.backends import native_cache
from snakebot.backends.native_cache import CompileError
from snakebot.backends.twin.readouts import Capsules

__all__ = ["C_SOURCE", "SCAN_FIELDS", "CompileError", "ContactScan", "load"]

C_SOURCE = r"""
#if defined(__clang__)
#pragma clang fp contract(off)
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif
#include <math.h>
#include <stdint.h>
#include <mujoco/mujoco.h>

/* out[0]: deepest penetration of a module into anything that is not a module (-inf: no such
   contact); out[1]: deepest penetration between two modules (-inf: none); out[2]: 1 when a
   module touches anything that is not a module, else 0; out[3]: when out[2] is 0, the height of
   the lowest capsule point above z = 0 (else left as it was); out[4]: the largest |qvel| of the
   joints at `dof`. `is_link` flags each of the model's `ngeom` geoms. */
void snakebot_twin_scan(const mjData* d, const unsigned char* is_link, int ngeom, int capsules,
                        const int64_t* geoms, const double* radius, const double* half,
                        int joints, const int64_t* dof, double* out) {
  double floor = -INFINITY, other = -INFINITY;
  int grounded = 0;
  for (int i = 0; i < d->ncon; i++) {
    int first = d->contact[i].geom[0], second = d->contact[i].geom[1];
    int link_first = first >= 0 && first < ngeom && is_link[first];
    int link_second = second >= 0 && second < ngeom && is_link[second];
    double depth = -d->contact[i].dist;
    if (link_first && link_second) {
      if (depth > other) other = depth;
    } else {
      grounded = 1;
      if (depth > floor) floor = depth;
    }
  }
  out[0] = floor;
  out[1] = other;
  out[2] = grounded;
  if (!grounded) {
    double lowest = INFINITY;
    for (int c = 0; c < capsules; c++) {
      int64_t g = geoms[c];
      double axis_z = fabs(d->geom_xmat[9 * g + 8]);
      double point = (d->geom_xpos[3 * g + 2] - radius[c]) - half[c] * axis_z;
      if (point < lowest) lowest = point;
    }
    out[3] = lowest;
  }
  double fastest = 0.0;
  for (int j = 0; j < joints; j++) {
    double speed = fabs(d->qvel[dof[j]]);
    if (speed > fastest) fastest = speed;
  }
  out[4] = fastest;
}
"""

SCAN_FIELDS = ("floor_m", "self_m", "grounded", "clearance_m", "max_speed_rad_s")
"""What ``ContactScan.scan`` fills, in order."""

_LIBRARY: ctypes.CDLL | None = None


def load() -> ctypes.CDLL:
    """The compiled scan, compiling it on first use; CompileError if impossible."""
    global _LIBRARY
    if _LIBRARY is None:
        library = native_cache.load_library("twin_health", C_SOURCE)
        function = library.snakebot_twin_scan
        function.restype = None
        function.argtypes = [ctypes.c_void_p, ctypes.c_void_p] + [ctypes.c_int] * 2
        function.argtypes += [ctypes.c_void_p] * 3 + [ctypes.c_int] + [ctypes.c_void_p] * 2
        _LIBRARY = library
    return _LIBRARY


class ContactScan:
    """The per-cycle scan of one twin model: ``scan(data)`` returns (floor penetration m,
    module-module penetration m, grounded, lowest capsule point m or None when grounded,
    fastest joint rad/s); the penetrations are -inf where there is no such contact. ``is_link``
    (ngeom,) flags the module capsules, ``dof_index`` (N,) the joints' DOF addresses.
    CompileError if the C cannot be built."""

    def __init__(
        self,
        model: mujoco.MjModel,
        capsules: Capsules,
        is_link: np.ndarray,
        dof_index: np.ndarray,
    ) -> None:
        self._function = load().snakebot_twin_scan
        # The C reads these; they live as long as the scan does (ctypes keeps no reference).
        self._keep = (
            np.ascontiguousarray(is_link, dtype=np.uint8),
            np.ascontiguousarray(capsules.geoms, dtype=np.int64),
            np.ascontiguousarray(capsules.radius_m, dtype=np.float64),
            np.ascontiguousarray(capsules.half_length_m, dtype=np.float64),
            np.ascontiguousarray(dof_index, dtype=np.int64),
        )
        flags, geoms, radius, half, dof = self._keep
        self._out = np.zeros(len(SCAN_FIELDS))
        self._args = (
            flags.ctypes.data,
            int(model.ngeom),
            int(geoms.shape[0]),
            geoms.ctypes.data,
            radius.ctypes.data,
            half.ctypes.data,
            int(dof.shape[0]),
            dof.ctypes.data,
            self._out.ctypes.data,
        )

    def scan(self, data: mujoco.MjData) -> tuple[float, float, bool, float | None, float]:
        """The scan of ``data`` now (see the class)."""
        self._function(data._address, *self._args)
        floor, other, grounded, clearance, speed = self._out.tolist()
        if grounded:
            return floor, other, True, None, speed
        return floor, other, False, clearance, speed
