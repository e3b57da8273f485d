"""A plain numpy integrator of Miller's model, written apart from MuJoCo to cross-check it.

Semi-implicit Euler on point masses, springs f = k (L - l) - D dl/dt, gravity, Miller's impulse
floor (a point below the floor is put back on it, loses its downward velocity, and Coulomb
friction takes at most mu times that impulse from its sliding), and the directional rule as the
paper writes it. It shares only the lattice and the muscle map (rest lengths) with the package.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snakebot.backends.softbody.lattice import build_lattice, rest_positions
from snakebot.backends.softbody.muscles import ChannelLayout, MuscleMap
from snakebot.config.body import BodyConfig
from snakebot.control.safety import smooth_ramp
from snakebot.gaits import Gait

GRAVITY = np.array([0.0, 0.0, -9.81])


@dataclass(frozen=True)
class ReferenceRun:
    """Start and end positions (P, 3) of a run."""

    start: np.ndarray
    end: np.ndarray

    @property
    def displacement(self) -> np.ndarray:
        """COM displacement (3,) in m."""
        return self.end.mean(axis=0) - self.start.mean(axis=0)  # type: ignore[no-any-return]

    @property
    def axis(self) -> np.ndarray:
        """Unit tail-to-head vector at the end."""
        rings = self.end.reshape(-1, 4, 3).mean(axis=1)
        axis = rings[0] - rings[-1]
        return axis / np.linalg.norm(axis)  # type: ignore[no-any-return]


def run_reference(
    body: BodyConfig,
    gait: Gait,
    *,
    duration_s: float,
    directional: bool,
    step_s: float = 2.5e-4,
    rate_hz: float = 100.0,
    ramp_s: float = 1.0,
) -> ReferenceRun:
    """Play ``gait`` on ``body`` for ``duration_s``; muscles update at ``rate_hz``."""
    lat = body.lattice
    lattice = build_lattice(lat.segments)
    muscles = MuscleMap(lattice, lat.segment_length_m, lat.width_m, lat.height_m)
    layout = ChannelLayout(body.muscles.channels, lat.segments)
    a, b = lattice.springs[:, 0], lattice.springs[:, 1]
    k, damping, mass = body.stiffness_n_per_m, body.damping_ns_per_m, lat.point_mass_kg
    radius, mu = lat.point_radius_m, body.ground.friction
    x = rest_positions(lat.segments, lat.segment_length_m, lat.width_m, lat.height_m, radius)
    v = np.zeros_like(x)
    start = x.copy()
    per_cycle = round(1.0 / (rate_hz * step_s))
    for cycle in range(round(duration_s * rate_hz)):
        t = cycle / rate_hz
        yaw, pitch, axial = layout.split(smooth_ramp(t / ramp_s) * gait.targets(t))
        scale = np.ones(lattice.rings)
        if body.muscles.volume_preservation:
            scale = muscles.ring_scale(muscles.segment_lengths(x))
        rest = muscles.rest_lengths(yaw, pitch, axial, scale)
        for _ in range(per_cycle):
            delta = x[b] - x[a]
            length = np.linalg.norm(delta, axis=1)
            unit = delta / length[:, None]
            rate = np.einsum("ij,ij->i", v[b] - v[a], unit)
            push = (k * (rest - length) - damping * rate)[:, None] * unit
            force = np.zeros_like(x)
            np.add.at(force, b, push)
            np.add.at(force, a, -push)
            v += step_s * (force / mass + GRAVITY)
            x += step_s * v
            _floor(x, v, radius, mu)
            if directional:
                _millers_rule(x, v, radius)
    return ReferenceRun(start, x)


def _floor(x: np.ndarray, v: np.ndarray, radius: float, mu: float) -> None:
    """Impulse floor at z = 0 for spheres of ``radius``, with Coulomb friction."""
    below = x[:, 2] < radius
    if not below.any():
        return
    x[below, 2] = radius
    normal = np.maximum(-v[below, 2], 0.0)
    v[below, 2] = np.maximum(v[below, 2], 0.0)
    sliding = v[below, :2]
    speed = np.linalg.norm(sliding, axis=1)
    keep = np.where(speed > 0, np.maximum(speed - mu * normal, 0.0) / np.maximum(speed, 1e-12), 0.0)
    v[below, :2] = sliding * keep[:, None]


def _millers_rule(x: np.ndarray, v: np.ndarray, radius: float, gap: float = 1e-3) -> None:
    """If S . V < 0 then V = V - S (S . V), for points close to the floor (the paper's loop)."""
    centres = x.reshape(-1, 4, 3).mean(axis=1)
    rings = len(centres)
    for p in np.flatnonzero(x[:, 2] <= radius + gap):
        ring = p // 4
        spine = centres[max(ring - 1, 0)] - centres[min(ring + 1, rings - 1)]
        spine /= np.linalg.norm(spine)
        along = spine @ v[p]
        if along < 0.0:
            v[p] -= spine * along
