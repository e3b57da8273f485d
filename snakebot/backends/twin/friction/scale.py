"""Scale friction: directional Coulomb friction in each link's own frame, on any ground.

MuJoCo's contact pairs give body-aligned friction only between a capsule and a plane
(locomotion.md §4); on a height field, a box or a cylinder the frame is world-aligned and lateral
undulation stops. Here the ground contacts carry only normal forces (condim 1) and a friction
force stands for the module's scales, wheels or skin. For every contact of a link with anything
but another link, with normal n and normal force f_n:

    a = the link's forward axis projected on the contact plane, l = n x a,
    F = -f_n [mu_f|b tanh(v_a / v0) a + mu_lat tanh(v_l / v0) l]

mu_f applies when v_a > 0 (sliding head-first) and mu_b when v_a < 0; backward >= forward models
scales (Miller 1988; Hu et al. 2009). Wheels and scales (forward < lateral): v is the link's COM
velocity and F acts at the COM (an axle does not roll sideways). Bare modules: v is the
material's velocity at the contact point and F acts there, so friction can roll the body
(rolling gaits). v0 regularises Coulomb's sign near zero speed; it is raised where the slope
mu N / v0 would overshoot in one explicit step (``h mu N`` times the inverse mass at the point of
action). The force uses the contact forces of the step before (one step of lag,
learning-softbody-terrain.md §3.2).

The force is computed inside ``mj_step`` by a ``mjcb_sensor`` callback: C through ctypes when a
compiler is available (scale_c.py), numpy otherwise, with a warning.
"""

from __future__ import annotations

import contextlib
import math
import os
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, Literal

import mujoco
import numpy as np

from snakebot.backends.twin.friction.layout import NUMERIC_NAME, SENSOR_NAME, Slot
from snakebot.errors import ConfigError

FrictionModel = Literal["auto", "pairs", "scale"]
FRICTION_MODELS: tuple[FrictionModel, ...] = ("auto", "pairs", "scale")
Implementation = Literal["c", "numpy"]
DEFAULT_V0_M_S = 0.01
_ENV_IMPLEMENTATION = "SNAKEBOT_SCALE_FRICTION"


@dataclass(frozen=True)
class ScaleFriction:
    """Coefficients of the scale model: sliding forward, backward and sideways; v0 in m/s.

    ConfigError (naming ``source``) unless all are finite and >= 0, backward >= forward and
    v0 > 0.
    """

    forward: float
    backward: float
    lateral: float
    v0_m_s: float = DEFAULT_V0_M_S
    source: str = "friction"

    def __post_init__(self) -> None:
        values = (self.forward, self.backward, self.lateral)
        if not all(math.isfinite(v) and v >= 0 for v in values):
            raise ConfigError(self.source, "", f"friction coefficients must be >= 0, got {values}")
        if self.backward < self.forward:
            raise ConfigError(
                self.source,
                "",
                f"backward friction {self.backward:g} is below forward {self.forward:g}: scales "
                "resist sliding tail-first at least as much as head-first",
            )
        if not (math.isfinite(self.v0_m_s) and self.v0_m_s > 0):
            raise ConfigError(self.source, "", f"v0 must be > 0 m/s, got {self.v0_m_s}")

    @property
    def at_contact_point(self) -> bool:
        """Bare modules (forward >= lateral) feel friction where they touch, so it can roll
        them (rolling gaits); wheels and scales (forward < lateral) at their centre of mass,
        as wheels on an axle do not roll sideways."""
        return self.forward >= self.lateral


def add_scale_friction(spec: mujoco.MjSpec, link_count: int, friction: ScaleFriction) -> None:
    """Add the parameter element and the per-link load sensor to ``spec``.

    The link geoms must already touch the ground with condim 1 (model_builder does that);
    :func:`bind_scale_friction` completes the model after compiling.
    """
    data = [0.0] * len(Slot)
    data[Slot.LINK_COUNT] = float(link_count)
    data[Slot.MU_FORWARD] = friction.forward
    data[Slot.MU_BACKWARD] = friction.backward
    data[Slot.MU_LATERAL] = friction.lateral
    data[Slot.V0_M_S] = friction.v0_m_s
    data[Slot.AT_CONTACT] = float(friction.at_contact_point)
    spec.add_numeric(name=NUMERIC_NAME, data=data)
    spec.add_sensor(
        name=SENSOR_NAME,
        type=mujoco.mjtSensor.mjSENS_USER,
        dim=link_count,
        needstage=mujoco.mjtStage.mjSTAGE_ACC,
        datatype=mujoco.mjtDataType.mjDATATYPE_POSITIVE,
    )


def bind_scale_friction(
    model: mujoco.MjModel, first_body: int, implementation: Implementation | None = None
) -> Implementation:
    """Point ``model``'s parameters at its link bodies (``first_body`` onward, consecutive) and
    install the callback; returns the implementation in use ("c" or "numpy").

    ``implementation`` None means $SNAKEBOT_SCALE_FRICTION, else C if it compiles (a warning and
    numpy if not).
    """
    start = model.numeric_adr[model.numeric(NUMERIC_NAME).id]
    model.numeric_data[start + Slot.FIRST_BODY] = first_body
    return install(implementation)


def install(implementation: Implementation | None = None) -> Implementation:
    """Make MuJoCo compute scale friction in every model that carries its elements."""
    choice = implementation or os.environ.get(_ENV_IMPLEMENTATION, "c")
    if choice not in ("c", "numpy"):
        raise ConfigError(_ENV_IMPLEMENTATION, "", f"expected c or numpy, got {choice!r}")
    if choice == "c":
        from snakebot.backends.twin.friction import scale_c

        try:
            library = scale_c.load()
        except scale_c.CompileError as exc:
            warnings.warn(
                f"scale friction runs in numpy, about half as fast as C: {exc}",
                RuntimeWarning,
                stacklevel=3,
            )
        else:
            if not library.snakebot_installed():
                mujoco.set_mjcb_sensor(None)
                library.snakebot_install()
            return "c"
    if mujoco.get_mjcb_sensor() is not numpy_callback:
        mujoco.set_mjcb_sensor(numpy_callback)
    return "numpy"


def ready_for_batch() -> None:
    """Make the installed sensor callback one ``mujoco.batch`` can run: batches take only C
    callbacks, and the callback is process-wide, so a numpy one left by an earlier twin (even
    for a model with no scale friction of its own) would stop every batch. It is swapped for the
    C callback, which computes the same forces for every model that carries them.

    ConfigError if that cannot be: $SNAKEBOT_SCALE_FRICTION asks for numpy, or C does not
    compile here.
    """
    if mujoco.get_mjcb_sensor() is not numpy_callback:
        return
    if os.environ.get(_ENV_IMPLEMENTATION) == "numpy":
        raise ConfigError(
            _ENV_IMPLEMENTATION,
            "numpy",
            "batched runs (tune, sysid) compute scale friction only in C: unset it or set c",
        )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # replaced by the error below
        if install("c") != "c":
            raise ConfigError(
                "scale friction",
                "",
                "batched runs (tune, sysid) compute it only in C, which did not compile here: "
                "install a C compiler (cc, gcc or clang) or set $CC",
            )


@contextlib.contextmanager
def python_callback_paused() -> Iterator[None]:
    """Lift the numpy callback while MuJoCo compiles: compiling runs the new model once, and
    the Python bindings cannot hand a callback a model they have not wrapped yet."""
    if mujoco.get_mjcb_sensor() is not numpy_callback:
        yield
        return
    mujoco.set_mjcb_sensor(None)
    try:
        yield
    finally:
        mujoco.set_mjcb_sensor(numpy_callback)


def numpy_callback(model: Any, data: Any, stage: int) -> None:
    """The scale-friction force in numpy: the same formula as the C callback."""
    if stage != mujoco.mjtStage.mjSTAGE_ACC:
        return
    nid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, NUMERIC_NAME)
    sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, SENSOR_NAME)
    if nid < 0 or sid < 0:
        return
    adr = model.numeric_adr[nid]
    params = model.numeric_data[adr : adr + len(Slot)]
    first, count = int(params[Slot.FIRST_BODY]), int(params[Slot.LINK_COUNT])
    if first < 1 or count < 1 or first + count > model.nbody:
        return  # not bound yet (MuJoCo runs the model once while compiling it)
    mu_f, mu_b, mu_l, v0 = params[Slot.MU_FORWARD : Slot.V0_M_S + 1]
    at_contact = params[Slot.AT_CONTACT] > 0.5
    bodies = slice(first, first + count)
    load = data.sensordata[model.sensor_adr[sid] : model.sensor_adr[sid] + count]
    xfrc = data.xfrc_applied[bodies]
    xfrc[:] = 0.0
    ncon = data.ncon
    contact = data.contact
    geom = contact.geom[:ncon]
    efc = contact.efc_address[:ncon]
    link = model.geom_bodyid[np.maximum(geom, 0)] - first
    inside = (link >= 0) & (link < count)
    keep = (inside[:, 0] != inside[:, 1]) & (efc >= 0) & (geom >= 0).all(axis=1)
    k = np.where(inside[:, 0], link[:, 0], link[:, 1])[keep]
    fn = data.efc_force[efc[keep]]
    load[:] = np.bincount(k, fn, minlength=count)
    if not k.size:
        return
    # COM velocity of each link from cvel (rotation, translation at the subtree COM).
    cvel = data.cvel[bodies]
    offset = data.xipos[bodies] - data.subtree_com[model.body_rootid[bodies]]
    velocity = cvel[:, 3:] + np.cross(cvel[:, :3], offset)
    h = model.opt.timestep
    mu_max = max(mu_f, mu_b, mu_l)
    reg = np.maximum(v0, h * mu_max * load / model.body_mass[bodies])
    normal = contact.frame[:ncon, :3][keep]
    axis = data.xmat[bodies][:, [0, 3, 6]][k]
    v = velocity[k]
    body = np.arange(first, first + count)[k]
    arm = np.zeros_like(v)
    if at_contact:  # velocity of the module's material at the contact point
        arm = contact.pos[:ncon][keep] - data.xipos[body]
        v = v + np.cross(cvel[k, :3], arm)

    def regularised(direction: np.ndarray) -> np.ndarray:
        """Per contact: v0, raised so the slope cannot overshoot at that point."""
        if not at_contact:
            return np.asarray(reg[k])
        frames = data.ximat[body].reshape(-1, 3, 3)
        local = np.einsum("nji,nj->ni", frames, np.cross(arm, direction))
        inverse = 1 / model.body_mass[body] + np.sum(local**2 / model.body_inertia[body], axis=1)
        return np.asarray(np.maximum(reg[k], h * mu_max * load[k] * inverse))

    a = axis - np.sum(axis * normal, axis=1, keepdims=True) * normal
    a_len = np.linalg.norm(a, axis=1)
    aligned = a_len >= 1e-6
    a = a / np.where(aligned, a_len, 1.0)[:, None]
    lateral = np.cross(normal, a)
    va, vl = np.sum(v * a, axis=1), np.sum(v * lateral, axis=1)
    mu_a = np.where(va > 0, mu_f, mu_b)
    along = (fn * mu_a * np.tanh(va / regularised(a)))[:, None] * a
    force = -along - (fn * mu_l * np.tanh(vl / regularised(lateral)))[:, None] * lateral
    # A link end-on to the surface: isotropic, with the lateral coefficient.
    vt = v - np.sum(v * normal, axis=1, keepdims=True) * normal
    vt_len = np.linalg.norm(vt, axis=1)
    slip = vt / np.maximum(vt_len, 1e-12)[:, None]
    iso = -(fn * mu_l * np.tanh(vt_len / regularised(slip)))[:, None] * slip
    force = np.where(aligned[:, None], force, iso)
    force[(fn <= 0) | (~aligned & (vt_len < 1e-12))] = 0.0
    np.add.at(xfrc[:, :3], k, force)
    np.add.at(xfrc[:, 3:], k, np.cross(arm, force))
