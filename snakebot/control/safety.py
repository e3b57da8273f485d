"""The safety layer between gait and backend: limits, joint speed, and amplitude ramps.

Whatever a gait asks for, what leaves here is finite, within the joint limits and no faster than
the servo can move; a gait that returns NaN stops the run instead of reaching a servo. A joint
that starts outside its limits (measured there at ``reset``) is brought inside at the slew limit,
moving only inwards, never stepped onto the limit.
"""

from __future__ import annotations

import math

import numpy as np

try:  # the ufunc np.clip calls: the same floats, without np.clip's 5 us of Python wrapping
    from numpy._core.umath import clip as _clip  # type: ignore[attr-defined]
except ImportError:  # numpy 1.26
    from numpy.core.umath import clip as _clip  # type: ignore[no-redef]

from snakebot.config.body import BodyConfig
from snakebot.config.schema import RobotConfig
from snakebot.errors import SafetyLimitError


def smooth_ramp(fraction: float) -> float:
    """A 0..1 ramp with zero slope at both ends (smoothstep), so ramps add no velocity jumps."""
    x = min(max(fraction, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


class SafetyLayer:
    """Clips, slew-limits and ramps joint targets (rad, shape (N,)) for one run.

    ``rest_rad`` is the pose amplitudes ramp from and to (straight, clipped into the limits).
    """

    def __init__(
        self,
        lower_rad: np.ndarray,
        upper_rad: np.ndarray,
        max_speed_rad_s: float,
        ramp_s: float,
        rest_rad: np.ndarray | None = None,
    ) -> None:
        self.lower_rad = np.asarray(lower_rad, dtype=float)
        self.upper_rad = np.asarray(upper_rad, dtype=float)
        if self.lower_rad.shape != self.upper_rad.shape or np.any(self.lower_rad > self.upper_rad):
            raise ValueError("lower_rad and upper_rad must have one shape and lower <= upper")
        if not max_speed_rad_s > 0:
            raise ValueError(f"max_speed_rad_s must be positive, got {max_speed_rad_s}")
        self.max_speed_rad_s = float(max_speed_rad_s)
        self.ramp_s = float(ramp_s)
        rest = np.zeros_like(self.lower_rad) if rest_rad is None else np.asarray(rest_rad, float)
        self.rest_rad = np.clip(rest, self.lower_rad, self.upper_rad)
        self._last: np.ndarray | None = None
        self._inside = False  # whether the last command is within the limits

    @classmethod
    def for_robot(cls, robot: RobotConfig | BodyConfig) -> SafetyLayer:
        """The envelope a robot (or mass-spring body) config asks for."""
        return cls(robot.lower_rad, robot.upper_rad, robot.max_speed_rad_s, robot.safety.ramp_s)

    @classmethod
    def clip_only(cls, robot: RobotConfig | BodyConfig) -> SafetyLayer:
        """The robot's joint limits and nothing else: no slew limit, no ramp. For command
        tables made for the servo (step tests, chirps, excitation records), whose every step
        and speed is the point of the test: inside the limits a row goes out as it is (to the
        bit where the rest pose is straight, 0 inside the limits). A NaN or a wrong shape still
        stops the run."""
        return cls(robot.lower_rad, robot.upper_rad, math.inf, 0.0)

    @property
    def limits_speed(self) -> bool:
        """False for a clip-only layer (no slew limit)."""
        return math.isfinite(self.max_speed_rad_s)

    def reset(self, measured_rad: np.ndarray) -> None:
        """Start from the measured pose, so the first command never jumps (even from a pose
        outside the limits: the slew limit then brings the joint in)."""
        measured = np.asarray(measured_rad, dtype=float)
        if measured.shape != self.lower_rad.shape or not np.isfinite(measured).all():
            raise SafetyLimitError(
                f"measured pose {measured} is not {self.lower_rad.shape} finite angles"
            )
        self._last = measured.copy()
        self._inside = bool(np.all((self.lower_rad <= measured) & (measured <= self.upper_rad)))

    def filter(self, target_rad: np.ndarray, dt_s: float, amplitude: float = 1.0) -> np.ndarray:
        """The command to send this cycle: ramped towards rest, clipped, slew-limited."""
        target = np.asarray(target_rad, dtype=float)
        lower, upper = self.lower_rad, self.upper_rad
        if target.shape != lower.shape:
            raise SafetyLimitError(f"gait returned shape {target.shape}, expected {lower.shape}")
        # A sum of finite angles is finite (unless it overflows: then look closer). Small
        # arrays sum faster as a list than numpy reduces them.
        total = sum(target.tolist()) if target.size <= 64 else float(target.sum())
        if not math.isfinite(total) and not np.isfinite(target).all():
            bad = np.flatnonzero(~np.isfinite(target)).tolist()
            raise SafetyLimitError(f"gait returned non-finite targets for joints {bad}; stopping")
        command = target - self.rest_rad
        command *= amplitude
        command += self.rest_rad
        _clip(command, lower, upper, out=command)
        last = self._last
        if last is not None and self.limits_speed:
            max_step = self.max_speed_rad_s * dt_s
            command -= last
            _clip(command, -max_step, max_step, out=command)
            command += last
            # Inside the limits, or on the way in from a start outside them: never outwards.
            if self._inside:  # then every command stays inside: the bounds are the limits
                _clip(command, lower, upper, out=command)
            else:
                _clip(command, np.minimum(lower, last), np.maximum(upper, last), out=command)
                self._inside = bool(np.all((lower <= command) & (command <= upper)))
        else:
            self._inside = True  # clipped into the limits above (no slew step to leave them)
        self._last = command
        return command  # type: ignore[no-any-return]
