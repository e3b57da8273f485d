"""Miller's directional friction: scales that slide forward and dig in backward.

For a point mass touching the ground, with S = (X[p-1] - X[p+1]) / |...| the local spine
direction towards the head (X the ring centres, the neighbours clamped at the ends)::

    if S . V < 0:  V = V - S (S . V)

removes the backward component of its velocity and keeps the rest (Miller 1988): an ideal
ratchet, backward friction without limit. With a finite ``backward_ratio`` r the scales resist
backward sliding with r times the floor's friction μ instead: on top of the floor's own μ·N
(MuJoCo's contact), the rule takes off at most (r - 1)·μ·N·h/m of the backward speed per step,
N the point's normal force in the step just taken, h the timestep, m the point's mass; r = 1 is
no directional friction, r = inf Miller's rule. It runs after every physics step on views of
MuJoCo's qpos and qvel, vectorised over the touching points.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from snakebot.backends.softbody.lattice import CORNERS, FloatArray, IntArray

if TYPE_CHECKING:
    import mujoco


def spine_directions(centres: FloatArray) -> FloatArray:
    """Unit spine direction (R, 3) at each ring from ring centres (R, 3), head = ring 0.

    Central differences inside, one-sided at the head and tail rings.
    """
    ahead = np.concatenate((centres[:1], centres[:-1]))
    behind = np.concatenate((centres[1:], centres[-1:]))
    spine = ahead - behind
    norm = np.linalg.norm(spine, axis=1, keepdims=True)
    out: FloatArray = spine / np.maximum(norm, 1e-12)
    return out


def remove_backward(velocity: FloatArray, spine: FloatArray, points: IntArray) -> int:
    """Apply Miller's rule in place to ``velocity`` (P, 3) rows ``points`` with their spine
    directions ``spine`` (len(points), 3); returns how many points were moving backward."""
    v = velocity[points]
    along = np.einsum("ij,ij->i", v, spine)
    backward = along < 0.0
    if not backward.any():
        return 0
    velocity[points[backward]] = v[backward] - spine[backward] * along[backward, None]
    return int(backward.sum())


class DirectionalFriction:
    """Miller's rule on a MuJoCo model's point masses, read from the contact list.

    ``point_geoms`` (P,) are the geom ids of the points in lattice order, ``geom_count`` the
    model's ngeom and ``start_positions`` (P, 3) where each point's slide joints read zero. A
    point touches the ground when it is in any contact (MuJoCo reports contacts up to the geom
    margin, so "close to the floor" includes a small gap, as in the paper).

    Written for one call per physics step: a dozen numpy operations on all P points, no Python
    loop, no allocation that depends on the contact count.
    """

    def __init__(self, point_geoms: IntArray, geom_count: int, start_positions: FloatArray) -> None:
        points = point_geoms.shape[0]
        # Geoms that are not points map to the spare slot P of the touch mask.
        self.geom_point = np.full(geom_count, points, dtype=np.intp)
        self.geom_point[point_geoms] = np.arange(points)
        self.point_ring = np.arange(points) // CORNERS
        rings = points // CORNERS
        self._ahead = np.maximum(np.arange(rings) - 1, 0)
        self._behind = np.minimum(np.arange(rings) + 1, rings - 1)
        start_centres = start_positions.reshape(rings, CORNERS, 3).mean(axis=1)
        self._start_spine = start_centres[self._ahead] - start_centres[self._behind]
        self._touch = np.zeros(points + 1, dtype=bool)
        self.enabled = True
        self.projected = 0
        self.backward_ratio = math.inf
        """μ_backward / μ of the floor; inf: Miller's ideal rule (``set_backward``)."""
        self._impulse_per_n = 0.0  # (r - 1) μ h / m: backward speed taken per newton of load

    def set_backward(
        self, ratio: float, friction: float, timestep_s: float, point_mass_kg: float
    ) -> None:
        """Finite backward friction: ``ratio`` (>= 1, or inf for Miller's rule) times the
        floor's ``friction`` coefficient, for points of ``point_mass_kg`` stepped every
        ``timestep_s``. ValueError for a ratio below 1 or not a number."""
        if not ratio >= 1.0:
            raise ValueError(f"backward friction ratio must be >= 1 (or inf), got {ratio}")
        self.backward_ratio = ratio
        finite = math.isfinite(ratio)
        per_n = (ratio - 1.0) * friction * timestep_s / point_mass_kg
        self._impulse_per_n = per_n if finite else 0.0

    @property
    def ideal(self) -> bool:
        """True for Miller's rule (no backward sliding at all)."""
        return math.isinf(self.backward_ratio)

    def touching(self, contact_geoms: IntArray) -> np.ndarray:
        """Bool mask (P,) of the points in the contact pairs (ncon, 2) of geom ids."""
        touch = self._touch
        touch[:] = False
        touch[self.geom_point[contact_geoms.reshape(-1)]] = True
        return touch[:-1]

    def apply(
        self,
        displacement: FloatArray,
        velocity: FloatArray,
        contact_geoms: IntArray,
        normal_n: FloatArray | None = None,
    ) -> None:
        """Project the velocities (P, 3, modified in place) of touching points that move backward.

        ``displacement`` (P, 3) is each point's position minus its start position (the slide
        joints' qpos); ``contact_geoms`` the contact list's (ncon, 2) geom ids; ``normal_n``
        (ncon,) each contact's normal force, N, which a finite ``backward_ratio`` needs.
        """
        if not self.enabled or contact_geoms.shape[0] == 0:
            return
        if not self.ideal:
            if normal_n is None:
                raise ValueError("finite backward friction needs the contacts' normal forces")
            self._apply_finite(displacement, velocity, contact_geoms, normal_n)
            return
        touch = self.touching(contact_geoms)
        rings = displacement.reshape(-1, CORNERS, 3).sum(axis=1)
        spine = self._start_spine + 0.25 * (rings[self._ahead] - rings[self._behind])
        spine /= np.sqrt(np.einsum("ij,ij->i", spine, spine))[:, None]
        spine = spine[self.point_ring]
        along = np.einsum("ij,ij->i", velocity, spine)
        along *= touch & (along < 0.0)
        velocity -= spine * along[:, None]
        self.projected += int(np.count_nonzero(along))

    def _spine_of_points(self, displacement: FloatArray) -> FloatArray:
        rings = displacement.reshape(-1, CORNERS, 3).sum(axis=1)
        spine = self._start_spine + 0.25 * (rings[self._ahead] - rings[self._behind])
        spine /= np.sqrt(np.einsum("ij,ij->i", spine, spine))[:, None]
        out: FloatArray = spine[self.point_ring]
        return out

    def _apply_finite(
        self,
        displacement: FloatArray,
        velocity: FloatArray,
        contact_geoms: IntArray,
        normal_n: FloatArray,
    ) -> None:
        """The finite rule: at most (r - 1) μ N h / m of backward speed off per step."""
        points = self.point_ring.shape[0]
        load = np.zeros(points + 1)
        for side in (0, 1):
            np.add.at(load, self.geom_point[contact_geoms[:, side]], normal_n)
        spine = self._spine_of_points(displacement)
        along = np.einsum("ij,ij->i", velocity, spine)
        taken = np.minimum(-along, self._impulse_per_n * load[:-1])
        taken *= along < 0.0
        velocity += spine * taken[:, None]
        self.projected += int(np.count_nonzero(taken))


def contact_normal_forces(data: mujoco.MjData) -> FloatArray:
    """Each contact's normal force (ncon,) N in the step just taken, from a pyramidal cone's
    constraint forces (the soft body's cone: the normal force is the sum of its 2(dim - 1)
    pyramid edges' forces)."""
    ncon = int(data.ncon)
    contact = data.contact
    address = contact.efc_address[:ncon]
    edges = 2 * (contact.dim[:ncon] - 1)
    force = data.efc_force
    out = np.zeros(ncon)
    for edge in range(int(edges.max(initial=0))):
        valid = (address >= 0) & (edge < edges)
        out[valid] += force[address[valid] + edge]
    return out
