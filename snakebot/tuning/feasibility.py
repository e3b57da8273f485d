"""Whether a gait is one the real servos can play: limits, speed, torque, and staying grounded."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snakebot.config.schema import RobotConfig
from snakebot.servo.dynamics import servo_dynamics
from snakebot.tuning.trace import FloatArray, Trace

SATURATION_FRACTION = 0.95
FLIPPED_UP_Z = -0.5
# Physics health (docs/physics.md): the twin's warning thresholds, as the tuner applies them.
MAX_UPSIDE_DOWN_FRACTION = 0.1
MAX_PENETRATION_FRACTION = 0.25
MAX_CHATTER = 0.25
MOVING_FRACTION = 0.05


@dataclass(frozen=True)
class Envelope:
    """What a playable gait stays inside, and when a run is cut short as hopeless.

    ``max_speed_rad_s`` is the safety layer's joint speed; ``no_load_speed_rad_s`` the servo's
    own. A run is airborne when no module is within ``contact_tolerance_m`` of the floor or the
    COM rose more than ``lift_limit_m`` above its resting height ``rest_com_z_m``. A joint may sit
    at its torque limit for ``max_saturation_s`` at a stretch. ``stop_after_s`` of continuous
    flight (or of lying upside down, unless ``allow_roll``) ends a run early. Lying upside down
    for more than ``MAX_UPSIDE_DOWN_FRACTION`` of the run in all (unless ``allow_roll``), sinking
    more than ``MAX_PENETRATION_FRACTION`` of ``radius_m`` into the floor (0: not checked) or
    chattering (docs/physics.md) makes a gait infeasible.
    """

    lower_rad: FloatArray
    upper_rad: FloatArray
    max_speed_rad_s: float
    no_load_speed_rad_s: float
    torque_limit_nm: float
    rest_com_z_m: float
    lift_limit_m: float
    contact_tolerance_m: float = 0.002
    max_saturation_s: float = 0.25
    stop_after_s: float = 0.25
    allow_roll: bool = False
    radius_m: float = 0.0

    @classmethod
    def for_robot(
        cls, robot: RobotConfig, rest_com_z_m: float, *, allow_roll: bool = False
    ) -> Envelope:
        """The envelope of ``robot``; the COM may rise two module radii before it is flying."""
        servo = servo_dynamics(robot.servo.physics, robot.gains)
        return cls(
            lower_rad=robot.lower_rad,
            upper_rad=robot.upper_rad,
            max_speed_rad_s=robot.max_speed_rad_s,
            no_load_speed_rad_s=servo.no_load_speed_rad_s,
            torque_limit_nm=servo.torque_limit_nm,
            rest_com_z_m=rest_com_z_m,
            lift_limit_m=2.0 * robot.link.radius_m,
            allow_roll=allow_roll,
            radius_m=robot.link.radius_m,
        )

    def airborne(self, com_z_m: FloatArray, clearance_m: FloatArray) -> np.ndarray:
        """Per sample: no floor contact, or the COM clearly lifted (bool, same shape)."""
        lifted = com_z_m - self.rest_com_z_m > self.lift_limit_m
        return np.asarray((clearance_m > self.contact_tolerance_m) | lifted)

    def flipped(self, up_z: FloatArray) -> np.ndarray:
        """Per sample: the head lies upside down (never, when rolling is allowed)."""
        if self.allow_roll:
            return np.zeros(np.shape(up_z), dtype=bool)
        return np.asarray(up_z < FLIPPED_UP_Z)

    def hopeless(
        self, com_m: FloatArray, clearance_m: FloatArray, head_quat: FloatArray
    ) -> tuple[np.ndarray, np.ndarray]:
        """(airborne, flipped): whether every sample of a window was in flight / upside down.

        ``com_m`` (..., W, 3), ``clearance_m`` (..., W) and ``head_quat`` (..., W, 4) hold W
        cycles; both results have the leading shape (...).
        """
        airborne = self.airborne(com_m[..., 2], clearance_m).all(axis=-1)
        up_z = 1.0 - 2.0 * (head_quat[..., 1] ** 2 + head_quat[..., 2] ** 2)
        flipped = self.flipped(up_z).all(axis=-1)
        return np.asarray(airborne), np.asarray(flipped)


@dataclass(frozen=True)
class Violations:
    """How far a run left the envelope; every field is 0 (or False) for a playable gait.

    ``joint_limit_rad``: worst request beyond a joint limit. ``speed_excess``: worst requested or
    measured joint speed over the allowed one, as a fraction (0.2 = 20 % too fast).
    ``saturation_excess_s``: longest stretch at the torque limit beyond the allowed one.
    ``airborne_fraction``: share of cycles off the ground. ``stopped``: why the run was cut short.
    Physics health (docs/physics.md): ``upside_down_fraction`` (share of cycles, counted over
    ``MAX_UPSIDE_DOWN_FRACTION`` unless rolling is allowed), ``penetration_excess`` (deepest
    floor penetration beyond ``MAX_PENETRATION_FRACTION``, in capsule radii), ``chatter_excess``
    (the worst joint's share of cycles with a velocity reversal beyond ``MAX_CHATTER``).
    """

    joint_limit_rad: float = 0.0
    speed_excess: float = 0.0
    saturation_excess_s: float = 0.0
    airborne_fraction: float = 0.0
    stopped: str = ""
    upside_down_fraction: float = 0.0
    upside_down_excess: float = 0.0
    penetration_excess: float = 0.0
    chatter_excess: float = 0.0

    @property
    def feasible(self) -> bool:
        """True when the gait stayed inside the envelope for the whole run."""
        return self.total == 0.0 and not self.stopped

    @property
    def total(self) -> float:
        """One number for ranking infeasible candidates (dimensionless, 0 when feasible)."""
        return (
            self.joint_limit_rad
            + self.speed_excess
            + self.saturation_excess_s
            + self.airborne_fraction
            + self.upside_down_excess
            + self.penetration_excess
            + self.chatter_excess
            + (1.0 if self.stopped else 0.0)
        )

    def as_dict(self) -> dict[str, object]:
        """JSON-ready fields plus ``feasible``."""
        return {
            "joint_limit_rad": self.joint_limit_rad,
            "speed_excess": self.speed_excess,
            "saturation_excess_s": self.saturation_excess_s,
            "airborne_fraction": self.airborne_fraction,
            "stopped": self.stopped,
            "upside_down_fraction": self.upside_down_fraction,
            "penetration_excess": self.penetration_excess,
            "chatter_excess": self.chatter_excess,
            "feasible": self.feasible,
        }


def assess(trace: Trace, envelope: Envelope, duration_s: float) -> Violations:
    """Measure a run against the envelope; a run cut short counts the missing time as airborne."""
    target = trace.target_rad
    beyond = np.maximum(target - envelope.upper_rad, envelope.lower_rad - target)
    limit = max(float(beyond.max(initial=0.0)), 0.0)
    requested = np.abs(np.diff(target, axis=0)).max(initial=0.0) / trace.dt_s
    measured = float(np.abs(trace.velocity_rad_s).max(initial=0.0))
    speed = max(
        requested / envelope.max_speed_rad_s - 1.0,
        measured / envelope.no_load_speed_rad_s - 1.0,
        0.0,
    )
    saturated = np.abs(trace.actuator_force_nm) >= SATURATION_FRACTION * envelope.torque_limit_nm
    longest = _longest_run(saturated) * trace.dt_s
    airborne = envelope.airborne(trace.com_m[:, 2], trace.clearance_m)
    planned = max(round(duration_s / trace.dt_s), trace.cycles, 1)
    missing = planned - trace.cycles
    upside_down = float(np.mean(trace.up_z < FLIPPED_UP_Z)) if trace.cycles else 0.0
    upside_down_excess = 0.0 if envelope.allow_roll else upside_down - MAX_UPSIDE_DOWN_FRACTION
    reversals = chatter(trace.velocity_rad_s, envelope.no_load_speed_rad_s)
    penetration = 0.0
    if envelope.radius_m > 0 and trace.cycles:
        depth = -float(trace.clearance_m.min()) / envelope.radius_m
        penetration = depth - MAX_PENETRATION_FRACTION
    return Violations(
        joint_limit_rad=limit,
        speed_excess=float(speed),
        saturation_excess_s=max(longest - envelope.max_saturation_s, 0.0),
        airborne_fraction=(int(airborne.sum()) + missing) / planned,
        stopped=trace.stop_reason,
        upside_down_fraction=upside_down,
        upside_down_excess=max(upside_down_excess, 0.0),
        penetration_excess=max(penetration, 0.0),
        chatter_excess=max(reversals - MAX_CHATTER, 0.0),
    )


def chatter(velocity_rad_s: FloatArray, no_load_speed_rad_s: float) -> float:
    """The worst joint's share of cycles (K, N) with a velocity reversal, both sides moving
    faster than ``MOVING_FRACTION`` of the no-load speed (1.0: reversing every cycle)."""
    if len(velocity_rad_s) < 2:
        return 0.0
    moving = np.abs(velocity_rad_s) > MOVING_FRACTION * no_load_speed_rad_s
    sign = np.where(moving, np.sign(velocity_rad_s), 0.0)
    reversals = (sign[1:] * sign[:-1]) < 0
    return float(reversals.sum(axis=0).max(initial=0)) / len(velocity_rad_s)


def _longest_run(flags: np.ndarray) -> int:
    """Longest run of consecutive True samples down axis 0, over all columns."""
    best = 0
    run = np.zeros(flags.shape[1:], dtype=int)
    for row in flags:
        run = np.where(row, run + 1, 0)
        best = max(best, int(run.max(initial=0)))
    return best
