"""The scale-friction force as a small C function: compiled with gcc at first use, cached, loaded
through ctypes and installed as MuJoCo's ``mjcb_sensor`` callback.

MuJoCo calls ``mjcb_sensor`` after the constraint solver of every step (for models with a user
sensor at the acceleration stage), so the callback sees that step's contact normal forces and
writes the friction forces for the next step into ``xfrc_applied``: the one-step lag of the
recipe in learning-softbody-terrain.md §3.2, inside ``mj_step`` itself. Stepping N steps at a
time, ``mujoco.rollout`` and ``mujoco.batch`` threads all get the friction without Python.

The source is kept here as a string, so the wheel needs no package data; the shared object is
cached under the user cache folder, keyed by a hash of the source and MuJoCo's version
(native_cache.py).
"""

from __future__ import annotations

import ctypes
from pathlib import Path

from snakebot.backends import native_cache
from snakebot.backends.native_cache import CompileError
from snakebot.backends.twin.friction.layout import NUMERIC_NAME, SENSOR_NAME, Slot

__all__ = ["C_SOURCE", "CompileError", "load", "object_path"]

_TEMPLATE = r"""
#include <math.h>
#include <string.h>
#include <mujoco/mujoco.h>

/* Layout of the numeric element (see layout.py). */
enum { FIRST = 0, COUNT, MU_F, MU_B, MU_L, V0, AT_CONTACT };

/* Inverse mass of body b for a force along unit d applied at offset r from its COM. */
static mjtNum inv_mass(const mjModel* m, const mjData* d, int b, const mjtNum r[3],
                       const mjtNum dir[3]) {
  mjtNum arm[3], local[3];
  mju_cross(arm, r, dir);
  mju_mulMatTVec3(local, d->ximat + 9*b, arm);
  const mjtNum* inertia = m->body_inertia + 3*b;
  mjtNum inv = 1 / m->body_mass[b];
  for (int i = 0; i < 3; i++) inv += local[i] * local[i] / inertia[i];
  return inv;
}

static void snakebot_scale_friction(const mjModel* m, mjData* d, int stage) {
  if (stage != mjSTAGE_ACC) return;
  int nid = mj_name2id(m, mjOBJ_NUMERIC, "%(numeric)s");
  int sid = mj_name2id(m, mjOBJ_SENSOR, "%(sensor)s");
  if (nid < 0 || sid < 0) return;
  const mjtNum* p = m->numeric_data + m->numeric_adr[nid];
  int first = (int)p[FIRST], count = (int)p[COUNT];
  if (first < 1 || count < 1 || first + count > m->nbody) return;   /* not bound yet */
  mjtNum mu_f = p[MU_F], mu_b = p[MU_B], mu_l = p[MU_L], v0 = p[V0];
  int at_contact = p[AT_CONTACT] > 0.5;
  mjtNum mu_max = fmax(fmax(mu_f, mu_b), mu_l);
  mjtNum h = m->opt.timestep;
  mjtNum* load = d->sensordata + m->sensor_adr[sid];   /* per link: summed normal force, N */
  mjtNum vel[6];
  mjtNum lin[3 * count], ang[3 * count], reg[count];
  memset(load, 0, count * sizeof(mjtNum));

  /* pass 1: normal load on each link from contacts with anything but another link */
  for (int i = 0; i < d->ncon; i++) {
    const mjContact* c = d->contact + i;
    if (c->efc_address < 0 || c->geom[0] < 0 || c->geom[1] < 0) continue;
    int k0 = m->geom_bodyid[c->geom[0]] - first, k1 = m->geom_bodyid[c->geom[1]] - first;
    int in0 = k0 >= 0 && k0 < count, in1 = k1 >= 0 && k1 < count;
    if (in0 == in1) continue;
    load[in0 ? k0 : k1] += d->efc_force[c->efc_address];
  }
  /* link COM velocities; regularisation speed large enough that the friction's slope,
     mu N / v0, cannot overshoot in one explicit step: h mu N / (m v0) <= 1 */
  for (int k = 0; k < count; k++) {
    int b = first + k;
    mj_objectVelocity(m, d, mjOBJ_BODY, b, vel, 0);
    lin[3*k] = vel[3]; lin[3*k+1] = vel[4]; lin[3*k+2] = vel[5];
    ang[3*k] = vel[0]; ang[3*k+1] = vel[1]; ang[3*k+2] = vel[2];
    reg[k] = fmax(v0, h * mu_max * load[k] / m->body_mass[b]);
    mju_zero(d->xfrc_applied + 6*b, 6);
  }
  /* pass 2: per contact, forward/backward along the link axis projected on the contact plane,
     lateral across it, each scaled by that contact's normal force */
  for (int i = 0; i < d->ncon; i++) {
    const mjContact* c = d->contact + i;
    if (c->efc_address < 0 || c->geom[0] < 0 || c->geom[1] < 0) continue;
    int k0 = m->geom_bodyid[c->geom[0]] - first, k1 = m->geom_bodyid[c->geom[1]] - first;
    int in0 = k0 >= 0 && k0 < count, in1 = k1 >= 0 && k1 < count;
    if (in0 == in1) continue;
    int k = in0 ? k0 : k1, b = first + k;
    mjtNum fn = d->efc_force[c->efc_address];
    if (fn <= 0) continue;
    const mjtNum* n = c->frame;
    mjtNum r[3] = {0, 0, 0}, v[3] = {lin[3*k], lin[3*k+1], lin[3*k+2]};
    if (at_contact) {  /* velocity of the module's material at the contact point */
      mjtNum spin[3];
      mju_sub3(r, c->pos, d->xipos + 3*b);
      mju_cross(spin, ang + 3*k, r);
      mju_addTo3(v, spin);
    }
    mjtNum ax[3] = {d->xmat[9*b], d->xmat[9*b+3], d->xmat[9*b+6]};
    mjtNum an = mju_dot3(ax, n);
    mjtNum a[3] = {ax[0] - an*n[0], ax[1] - an*n[1], ax[2] - an*n[2]};
    mjtNum alen = mju_norm3(a);
    mjtNum* f = d->xfrc_applied + 6*b;
    if (alen < 1e-6) {           /* link end-on to the surface: isotropic, lateral coefficient */
      mjtNum vn = mju_dot3(v, n);
      mjtNum t[3] = {v[0] - vn*n[0], v[1] - vn*n[1], v[2] - vn*n[2]};
      mjtNum tlen = mju_norm3(t);
      if (tlen < 1e-12) continue;
      mjtNum dir[3] = {t[0] / tlen, t[1] / tlen, t[2] / tlen};
      mjtNum rg = reg[k];
      if (at_contact) rg = fmax(rg, h * mu_max * load[k] * inv_mass(m, d, b, r, dir));
      mjtNum s = -fn * mu_l * tanh(tlen / rg) / tlen;
      mjtNum force[3] = {s*t[0], s*t[1], s*t[2]}, torque[3];
      mju_addTo3(f, force);
      mju_cross(torque, r, force);
      mju_addTo3(f + 3, torque);
      continue;
    }
    a[0] /= alen; a[1] /= alen; a[2] /= alen;
    mjtNum l[3];
    mju_cross(l, n, a);
    mjtNum va = mju_dot3(v, a), vl = mju_dot3(v, l);
    mjtNum ra = reg[k], rl = reg[k];
    if (at_contact) {
      ra = fmax(ra, h * mu_max * load[k] * inv_mass(m, d, b, r, a));
      rl = fmax(rl, h * mu_max * load[k] * inv_mass(m, d, b, r, l));
    }
    mjtNum sa = -fn * (va > 0 ? mu_f : mu_b) * tanh(va / ra);
    mjtNum sl = -fn * mu_l * tanh(vl / rl);
    mjtNum force[3] = {sa*a[0] + sl*l[0], sa*a[1] + sl*l[1], sa*a[2] + sl*l[2]}, torque[3];
    mju_addTo3(f, force);
    mju_cross(torque, r, force);
    mju_addTo3(f + 3, torque);
  }
}

void snakebot_install(void) { mjcb_sensor = snakebot_scale_friction; }
void snakebot_uninstall(void) {
  if (mjcb_sensor == snakebot_scale_friction) mjcb_sensor = 0;
}
int snakebot_installed(void) { return mjcb_sensor == snakebot_scale_friction; }
"""
C_SOURCE = _TEMPLATE.replace("%(numeric)s", NUMERIC_NAME).replace("%(sensor)s", SENSOR_NAME)

# The C enum above must match layout.Slot.
assert [slot.value for slot in Slot] == list(range(len(Slot)))


def object_path() -> Path:
    """The cached shared object for this source and this MuJoCo."""
    return native_cache.object_path("scale_friction", C_SOURCE)


_LIBRARY: ctypes.CDLL | None = None


def load() -> ctypes.CDLL:
    """The compiled callback library, compiling it on first use; CompileError if impossible."""
    global _LIBRARY
    if _LIBRARY is None:
        library = native_cache.load_library("scale_friction", C_SOURCE)
        for name in ("snakebot_install", "snakebot_uninstall"):
            getattr(library, name).restype = None
        library.snakebot_installed.restype = ctypes.c_int
        _LIBRARY = library
    return _LIBRARY
