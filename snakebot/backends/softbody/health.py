"""Physics health of a mass-spring body: is what MuJoCo computed a body Miller could have drawn?

The rigid twin's checks (twin/health.py) judge capsules and servos; a lattice of point masses
and springs fails differently, so it has its own four, sampled once per control period:

- point-mass penetration: how deep a point's sphere sinks into the ground, against its radius;
- airborne time: control periods in which no point touches the ground;
- spring strain: how far any spring is from its rest length, |l / L - 1| (a lattice that folds
  or tears stretches springs far beyond what the muscles ask: the commanded shapes never strain
  a spring, since every rest length is its length in the target shape);
- energy: the kinetic energy of the points against what could have made it, the springs'
  positive work (every spring's force times its rate of length where positive, integrated every
  physics step: all the motion the springs give the points passes through it) plus the height
  the body lost (m g Δz); more than that is energy from nowhere, the signature of an
  integration going unstable.

Past a warning threshold the summary lists a warning; past a hard one the run stops with the
rigid twin's ``PhysicsHealthError``, at the time it happened. Limits and why:
docs/soft-bodies.md, "Physics health".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from snakebot.errors import PhysicsHealthError

GRAVITY_M_S2 = 9.81


@dataclass(frozen=True)
class BodyHealthLimits:
    """Warning and hard thresholds of a mass-spring body's physics checks.

    Penetrations are fractions of a point's radius (a worm landing from the 4 cm cliff sinks
    a point 2.1 radii for 10 ms and recovers: a warning; 3 radii puts the sphere's centre two
    radii under the surface, from where contacts push it through rather than back); strain is
    |l / L - 1| of the worst spring (the snake body's sidewinding reaches 0.55: a warning; 1.0 is
    a spring doubled or collapsed, a torn or inverted lattice);
    ``energy_*`` is the kinetic energy of the points over the springs' positive work plus the
    potential energy the body lost plus ``energy_floor_j`` (1.0: all of it became motion,
    which a damped body never does). A period is airborne when no point touches the ground and
    the lowest point is more than ``contact_tolerance_m`` above it. ``hard`` False turns hard
    limits into warnings.
    """

    penetration_warn: float = 0.5
    penetration_error: float = 3.0
    airborne_warn: float = 0.05
    strain_warn: float = 0.5
    strain_error: float = 1.0
    energy_warn: float = 1.0
    energy_error: float = 5.0
    energy_floor_j: float = 1e-4
    contact_tolerance_m: float = 0.001
    hard: bool = True


DEFAULT_BODY_LIMITS = BodyHealthLimits()


class BodyHealthMonitor:
    """Accumulates the health of one mass-spring run; ``sample`` after every control period.

    ``point_geoms`` (P,) are the points' sphere geoms, ``point_bodies`` (P,) their bodies, all of
    ``radius_m``; every other geom is ground. The springs are the model's actuators, each on a
    tendon whose rest length is its ``ctrl``. ``data`` is the state the account starts from (the
    height the body's fall is counted from).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        point_geoms: np.ndarray,
        point_bodies: np.ndarray,
        radius_m: float,
        limits: BodyHealthLimits = DEFAULT_BODY_LIMITS,
    ) -> None:
        self.limits = limits
        is_point = np.zeros(model.ngeom, dtype=bool)
        is_point[point_geoms] = True
        self._is_point = is_point
        self._bodies = np.asarray(point_bodies)
        self._radius = radius_m
        self._mass = model.body_mass[self._bodies].copy()  # (P,)
        self._total_mass = float(self._mass.sum())
        self._tendons = model.actuator_trnid[:, 0].copy()  # the spring of each actuator
        self._start_z = self._com_z(data)
        self.cycles = 0
        self.max_penetration_m = 0.0
        self.max_strain = 0.0
        self.max_kinetic_j = 0.0
        self.max_energy_ratio = 0.0
        self._airborne_cycles = 0

    def sample(self, data: mujoco.MjData, work_j: float) -> None:
        """Account the control period ending now; ``work_j`` is the springs' positive work since
        the start, J. Raises PhysicsHealthError past a hard limit."""
        limits = self.limits
        self.cycles += 1
        z = data.xpos[self._bodies, 2]
        com_z = float(self._mass @ z) / self._total_mass
        grounded = False
        ncon = data.ncon
        if ncon:
            geoms = data.contact.geom[:ncon]
            ground = ~(self._is_point[geoms[:, 0]] & self._is_point[geoms[:, 1]])
            if ground.any():
                grounded = True
                depth = float(-data.contact.dist[:ncon][ground].min())
                self.max_penetration_m = max(self.max_penetration_m, depth)
        if not grounded and float(z.min()) - self._radius > limits.contact_tolerance_m:
            self._airborne_cycles += 1
        rest = data.ctrl
        strain = float(np.abs(data.ten_length[self._tendons] / rest - 1.0).max(initial=0.0))
        self.max_strain = max(self.max_strain, strain)
        velocity = data.qvel.reshape(-1, 3)
        kinetic = 0.5 * float(self._mass @ np.einsum("ij,ij->i", velocity, velocity))
        self.max_kinetic_j = max(self.max_kinetic_j, kinetic)
        budget = work_j + self._total_mass * GRAVITY_M_S2 * max(self._start_z - com_z, 0.0)
        ratio = kinetic / (budget + limits.energy_floor_j)
        self.max_energy_ratio = max(self.max_energy_ratio, ratio)
        if not limits.hard:
            return
        time_s = float(data.time)
        if self.max_penetration_m > limits.penetration_error * self._radius:
            raise PhysicsHealthError(
                time_s,
                "point penetration",
                f"a point sank {self.max_penetration_m * 1e3:.2f} mm into the ground (point "
                f"radius {self._radius * 1e3:.1f} mm)",
            )
        if strain > limits.strain_error:
            raise PhysicsHealthError(
                time_s,
                "spring strain",
                f"a spring is {strain:.0%} away from its rest length (limit "
                f"{limits.strain_error:.0%}): stiffer springs need a shorter timestep_s",
            )
        if not math.isfinite(ratio) or ratio > limits.energy_error:
            raise PhysicsHealthError(
                time_s,
                "energy",
                f"the points move with {kinetic:.3g} J, {ratio:.1f} x what the springs put in "
                f"({work_j:.3g} J) and the body's fall could give",
            )

    def _com_z(self, data: mujoco.MjData) -> float:
        """Height of the points' centre of mass, m."""
        return float(self._mass @ data.xpos[self._bodies, 2]) / self._total_mass

    def summary(self, energy_injected_j: float, spring_work_j: float) -> dict[str, object]:
        """JSON-ready health figures and the warnings past ``limits`` (docs/soft-bodies.md);
        ``energy_injected_j`` is the muscles' positive work over the run, ``spring_work_j``
        every spring's (the energy check's budget)."""
        limits = self.limits
        airborne = self._airborne_cycles / max(self.cycles, 1)
        radius_mm = self._radius * 1e3
        out: dict[str, object] = {
            "max_floor_penetration_mm": self.max_penetration_m * 1e3,
            "point_radius_mm": radius_mm,
            "airborne_fraction": airborne,
            "max_spring_strain": self.max_strain,
            "energy_injected_j": energy_injected_j,
            "spring_work_j": spring_work_j,
            "max_kinetic_energy_j": self.max_kinetic_j,
            "max_energy_ratio": self.max_energy_ratio,
        }
        warnings: list[str] = []
        if self.max_penetration_m > limits.penetration_warn * self._radius:
            warnings.append(
                f"point penetration {self.max_penetration_m * 1e3:.2f} mm is over "
                f"{limits.penetration_warn:.0%} of the {radius_mm:.1f} mm point radius"
            )
        if airborne > limits.airborne_warn:
            warnings.append(f"no point touched the ground for {airborne:.0%} of the control cycles")
        if self.max_strain > limits.strain_warn:
            warnings.append(
                f"a spring was {self.max_strain:.0%} away from its rest length (warning "
                f"above {limits.strain_warn:.0%})"
            )
        if self.max_energy_ratio > limits.energy_warn:
            warnings.append(
                f"the points' kinetic energy reached {self.max_energy_ratio:.2f} x the springs' "
                "work plus the body's fall: energy from nowhere"
            )
        out["warnings"] = warnings
        return out
