"""One control period of the twin in C: the physics steps, their work and the period's readouts.

A twin cycle used to pay a few dozen small Python and numpy calls around the physics: the
divergence check's warning counters before and after, the work integral, the servo torque, the
copies of the joint positions and speeds, the body's COM, head orientation and angular velocity
and the physics-health scan of the contacts. Here all of that is one ctypes call per period that
fills one fresh buffer (``Layout``), with the same arithmetic in the same order as the Python
path it replaces (``readouts.servo_torque_nm`` and ``step_work_j``, the health scan of
``health_c``; no fused multiply-add), so every state, body state, health figure and work total
is the Python path's bit for bit (tests/integration/twin/test_twin_period_c.py holds them to
it). The gyro's turn into the head's frame stays in numpy (its matmul rounds differently from a
plain C loop). Compiled and cached as the other helpers are (native_cache.py); without a compiler
the twin steps in Python with a warning.
"""

from __future__ import annotations

import ctypes

import mujoco
import numpy as np

from snakebot.backends import native_cache
from snakebot.backends.native_cache import CompileError
from snakebot.backends.twin import health_c
from snakebot.backends.twin.readouts import Capsules

__all__ = ["C_SOURCE", "CompileError", "Layout", "PeriodStepper", "load"]

C_SOURCE = (
    health_c.C_SOURCE
    + r"""
/* The warnings MuJoCo counts when it resets an unstable simulation (readouts.UNSTABLE_WARNINGS). */
static int snakebot_unstable(const mjData* d) {
  return d->warning[mjWARN_BADQACC].number + d->warning[mjWARN_BADQPOS].number
         + d->warning[mjWARN_BADQVEL].number;
}

typedef struct {
  int joints;                  /* N */
  const int64_t* qpos;         /* (N,) the joints' qpos addresses */
  const int64_t* dof;          /* (N,) their DOF addresses; actuator j drives joint j */
  int head;                    /* the head body */
  const unsigned char* is_link;  /* the health scan's arguments (health_c) */
  int ngeom;
  int capsules;
  const int64_t* geoms;
  const double* radius;
  const double* half;
  double* out;                 /* the readouts (Layout); the work totals stay there between calls */
} snakebot_period;

/* `steps` physics steps, then the period's readouts into `out` (Layout in period_c.py):
   positions, speeds, servo torques (N each), the period's positive work (N: max(torque *
   speed, 0) summed over the steps, times the timestep), the work totals plus it (N, in place:
   the totals of the calls so far), the head subtree's COM (3), the
   head's quaternion (4), its angular velocity in the world frame (3), the health scan (5, only
   when `scan`), the count of unstable-simulation warnings the steps added and the time before
   them. */
void snakebot_twin_period(const mjModel* m, mjData* d, const snakebot_period* p, int steps,
                          int scan) {
  int n = p->joints;
  double* out = p->out;
  const int64_t* dof = p->dof;
  double* work = out + 3 * n;
  int before = snakebot_unstable(d);
  double time_before = d->time;
  for (int j = 0; j < n; j++) work[j] = 0.0;
  for (int i = 0; i < steps; i++) {
    mj_step(m, d);
    for (int j = 0; j < n; j++) {
      double speed = d->qvel[dof[j]];
      double power = (d->actuator_force[j] - m->dof_damping[dof[j]] * speed) * speed;
      work[j] += power > 0.0 ? power : 0.0;
    }
  }
  for (int j = 0; j < n; j++) {
    work[j] *= m->opt.timestep;
    out[4 * n + j] = out[4 * n + j] + work[j];
    double speed = d->qvel[dof[j]];
    out[j] = d->qpos[p->qpos[j]];
    out[n + j] = speed;
    out[2 * n + j] = d->actuator_force[j] - m->dof_damping[dof[j]] * speed;
  }
  double* body = out + 5 * n;
  for (int k = 0; k < 3; k++) body[k] = d->subtree_com[3 * p->head + k];
  for (int k = 0; k < 4; k++) body[3 + k] = d->xquat[4 * p->head + k];
  double velocity[6];
  mj_objectVelocity(m, d, mjOBJ_BODY, p->head, velocity, 0);
  for (int k = 0; k < 3; k++) body[7 + k] = velocity[k];
  if (scan) {
    snakebot_twin_scan(d, p->is_link, p->ngeom, p->capsules, p->geoms, p->radius, p->half, n,
                       dof, body + 10);
  }
  body[15] = snakebot_unstable(d) - before;
  body[16] = time_before;
}
"""
)


class _Period(ctypes.Structure):
    _fields_ = [
        ("joints", ctypes.c_int),
        ("qpos", ctypes.c_void_p),
        ("dof", ctypes.c_void_p),
        ("head", ctypes.c_int),
        ("is_link", ctypes.c_void_p),
        ("ngeom", ctypes.c_int),
        ("capsules", ctypes.c_int),
        ("geoms", ctypes.c_void_p),
        ("radius", ctypes.c_void_p),
        ("half", ctypes.c_void_p),
        ("out", ctypes.c_void_p),
    ]


_LIBRARY: ctypes.CDLL | None = None


def load() -> ctypes.CDLL:
    """The compiled period library, compiling it on first use; CompileError if impossible."""
    global _LIBRARY
    if _LIBRARY is None:
        library = native_cache.load_library("twin_period", C_SOURCE)
        function = library.snakebot_twin_period
        function.restype = None
        function.argtypes = [ctypes.c_void_p] * 3 + [ctypes.c_int] * 2
        _LIBRARY = library
    return _LIBRARY


class Layout:
    """Where each readout sits in a period's buffer of ``size`` floats, for N ``joints``:
    slices for the (N,) arrays and the body's parts, indices for the two scalars.

    ``position`` (N,) rad, ``velocity`` (N,) rad/s, ``torque`` (N,) N*m (the servos' output torque,
    ``readouts.servo_torque_nm``), ``work`` (N,) J (each joint's positive work in the period,
    ``readouts.step_work_j``), ``total`` (N,) J (each joint's work since the stepper began or its
    ``restart``), ``com`` (3,) m (the head subtree's, the whole snake's, centre of mass), ``quat``
    (4,) (the head's orientation, w x y z), ``angular`` (3,) rad/s (the head's angular velocity in
    the world frame, ``mj_objectVelocity``), ``scan`` (5,) (``health_c.SCAN_FIELDS``, filled only
    when asked for); ``unstable`` the count of unstable-simulation warnings the steps added and
    ``time_before`` the robot time before them, s.
    """

    __slots__ = (
        "angular",
        "com",
        "joints",
        "position",
        "quat",
        "scan",
        "size",
        "time_before",
        "torque",
        "total",
        "unstable",
        "velocity",
        "work",
    )

    def __init__(self, joints: int) -> None:
        n = self.joints = joints
        self.position, self.velocity, self.torque, self.work, self.total = (
            slice(k * n, (k + 1) * n) for k in range(5)
        )
        body = 5 * n
        self.com = slice(body, body + 3)
        self.quat = slice(body + 3, body + 7)
        self.angular = slice(body + 7, body + 10)
        self.scan = slice(body + 10, body + 15)
        self.unstable, self.time_before = body + 15, body + 16
        self.size = body + 17


class PeriodStepper:
    """Steps ``model``/``data`` one control period at a time and reads the period out, for the
    joints at qpos addresses ``qpos_index`` and DOFs ``dof_index`` (N,), the head body
    ``head_id`` and the module ``capsules`` (the health scan's). CompileError if the C cannot be
    built."""

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        qpos_index: np.ndarray,
        dof_index: np.ndarray,
        head_id: int,
        capsules: Capsules,
    ) -> None:
        self._function = load().snakebot_twin_period
        self.layout = Layout(len(dof_index))
        self._out = np.zeros(self.layout.size)  # the C writes here; each period copies it out
        is_link = np.zeros(model.ngeom, dtype=np.uint8)
        is_link[capsules.geoms] = 1
        # The C reads these; they live as long as the stepper does (ctypes keeps no reference).
        self._keep = (
            np.ascontiguousarray(qpos_index, dtype=np.int64),
            np.ascontiguousarray(dof_index, dtype=np.int64),
            is_link,
            np.ascontiguousarray(capsules.geoms, dtype=np.int64),
            np.ascontiguousarray(capsules.radius_m, dtype=np.float64),
            np.ascontiguousarray(capsules.half_length_m, dtype=np.float64),
        )
        qpos, dof, flags, geoms, radius, half = self._keep
        self._period = _Period(
            len(dof),
            qpos.ctypes.data,
            dof.ctypes.data,
            head_id,
            flags.ctypes.data,
            int(model.ngeom),
            len(geoms),
            geoms.ctypes.data,
            radius.ctypes.data,
            half.ctypes.data,
            self._out.ctypes.data,
        )
        self._pointers = (model._address, data._address, ctypes.addressof(self._period))

    def restart(self, total_j: np.ndarray) -> None:
        """Count the work totals from ``total_j`` (N,) J on (zeros at connect and reset)."""
        self._out[self.layout.total] = total_j

    def advance(self, steps: int, scan: bool) -> np.ndarray:
        """``steps`` physics steps; the period's readouts in a new buffer (``layout``), the
        health scan in it when ``scan``."""
        model, data, period = self._pointers
        self._function(model, data, period, steps, scan)
        return self._out.copy()
