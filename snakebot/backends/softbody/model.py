"""Build a mass-spring body's MuJoCo model with ``mujoco.MjSpec`` (reference §2.1, §2.3).

- Each point mass is a body with three slide joints (so ``qvel`` is its world velocity, and
  Miller's velocity rule maps one to one) and a small sphere for contacts.
- Each spring is a spatial tendon between the two points' sites, driven by a ``position``
  actuator with kp = k and kv = D: the actuator's ``ctrl`` is the spring's rest length L, so the
  force along the spring is exactly k (L - l) - D dl/dt.
- Points reach the floor and the terrain (bit 1) but not each other.
- A skin (snakebot.backends.softbody.skin) draws the body as a smooth surface; points and springs
  sit in geom/tendon group 3, hidden by default (MuJoCo's viewer shows them on key 3).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from snakebot.backends.softbody.lattice import Lattice, build_lattice, rest_positions
from snakebot.backends.softbody.skin import add_skin
from snakebot.backends.twin.model_builder import SCENE_PATH
from snakebot.backends.twin.terrain.cliff import Cliff
from snakebot.config.body import BodyConfig

# Points touch bit 1 (floor, terrain) only; their own bit 4 is nobody's affinity.
_POINT_CONTYPE, _POINT_CONAFFINITY = 4, 1
# Contacts are reported up to this gap (but push only on touch): Miller's "close to the floor".
CONTACT_GAP_M = 0.001
_SLIDE_AXES = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def point_name(index: int) -> str:
    """Body name of point ``index`` (ring index // 4, corner index % 4)."""
    return f"p{index // 4}_{index % 4}"


def spring_name(index: int) -> str:
    """Tendon and actuator name of spring ``index``."""
    return f"spring{index}"


@dataclass(frozen=True)
class BodyModel:
    """A compiled body: the model, its lattice, the points' start positions and geom ids."""

    model: mujoco.MjModel
    lattice: Lattice
    start_positions: np.ndarray
    point_geoms: np.ndarray


def build_body_spec(
    body: BodyConfig,
    *,
    friction: float | None = None,
    terrain: Cliff | None = None,
    scene_path: str | None = None,
) -> mujoco.MjSpec:
    """An MjSpec of ``body`` on the twin's scene; ``friction`` overrides ``ground.friction``.

    Compile it, or ``to_xml()`` it for MuJoCo's viewer.
    """
    spec = mujoco.MjSpec.from_file(scene_path or str(SCENE_PATH))
    spec.modelname = body.name
    spec.compiler.degree = False
    spec.option.timestep = body.timestep_s
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_PYRAMIDAL
    lat = body.lattice
    lattice = build_lattice(lat.segments)
    lift = lat.point_radius_m + (terrain.start_height_m if terrain is not None else 0.0)
    positions = rest_positions(lat.segments, lat.segment_length_m, lat.width_m, lat.height_m, lift)
    mu = body.ground.friction if friction is None else friction
    world = spec.worldbody
    for index, position in enumerate(positions):
        point = world.add_body(name=point_name(index), pos=position.tolist())
        for axis_index, axis in enumerate(_SLIDE_AXES):
            point.add_joint(
                name=f"{point_name(index)}_{'xyz'[axis_index]}",
                type=mujoco.mjtJoint.mjJNT_SLIDE,
                axis=list(axis),
            )
        point.add_geom(
            name=f"{point_name(index)}_geom",
            type=mujoco.mjtGeom.mjGEOM_SPHERE,
            size=[lat.point_radius_m, 0, 0],
            mass=lat.point_mass_kg,
            contype=_POINT_CONTYPE,
            conaffinity=_POINT_CONAFFINITY,
            condim=3,
            priority=1,  # the point's friction wins over the floor's default 1.0
            friction=[mu, 0.005, 0.0001],
            margin=CONTACT_GAP_M,
            gap=CONTACT_GAP_M,
            rgba=[0.8, 0.35, 0.3, 1] if index < 4 else [0.35, 0.3, 0.3, 1],
            group=3,  # hidden under the skin by default
        )
        point.add_site(name=f"{point_name(index)}_site", group=3)
    stiffness, damping = body.stiffness_n_per_m, body.damping_ns_per_m
    for index, (a, b) in enumerate(lattice.springs):
        tendon = spec.add_tendon(name=spring_name(index), rgba=[0.9, 0.8, 0.2, 1], group=3)
        tendon.wrap_site(f"{point_name(int(a))}_site")
        tendon.wrap_site(f"{point_name(int(b))}_site")
        actuator = spec.add_actuator(name=spring_name(index), target=spring_name(index))
        actuator.trntype = mujoco.mjtTrn.mjTRN_TENDON
        actuator.set_to_position(kp=stiffness, kv=damping)
        actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    add_skin(
        spec,
        [point_name(i) for i in range(lattice.points)],
        positions,
        inflate_m=lat.point_radius_m,
    )
    if terrain is not None:
        terrain.add_to(spec)
    length = body.body_length_m
    world.add_camera(
        name="track",
        mode=mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM,
        pos=[-length / 2, -1.6 * length, 1.1 * length + lift],
        xyaxes=[1, 0, 0, 0, 0.57, 0.82],
    )
    return spec


def build_body_model(
    body: BodyConfig, *, friction: float | None = None, terrain: Cliff | None = None
) -> BodyModel:
    """Compile the body; returns the model, its lattice, start positions (P, 3) and point geoms."""
    spec = build_body_spec(body, friction=friction, terrain=terrain)
    model = spec.compile()
    lattice = build_lattice(body.lattice.segments)
    geoms = np.array(
        [model.geom(f"{point_name(i)}_geom").id for i in range(lattice.points)], dtype=np.intp
    )
    bodies = np.array([model.body(point_name(i)).id for i in range(lattice.points)])
    return BodyModel(model, lattice, model.body_pos[bodies].copy(), geoms)
