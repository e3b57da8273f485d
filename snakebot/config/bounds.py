"""The physically sensible range of every number in a robot, servo or body file.

The loader refuses a value outside its range with a ConfigError naming the file and the key, and
docs/config.md lists the same table (a test keeps the two in step). The ranges are wide enough
for any Dynamixel snake on a desk and narrow enough that a typo (``1e308``, ``-1``, ``1e-300``)
cannot reach the control loop or MuJoCo: a 1e308 s ramp never ends, a 1e308 kg link does not
compile.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from snakebot.config.schema import MAX_ACTUATOR_DELAY_S


@dataclass(frozen=True)
class Bounds:
    """``low`` to ``high`` in ``unit`` (``low`` itself excluded when ``low_open``); ``why`` says
    what the range covers."""

    low: float
    high: float
    unit: str
    why: str
    low_open: bool = False

    def contains(self, value: float) -> bool:
        """Whether ``value`` is inside the range."""
        above = value > self.low if self.low_open else value >= self.low
        return above and value <= self.high

    def describe(self) -> str:
        """The range as text, e.g. ``(0, 1]`` or ``[0.01, 1] m``."""
        text = f"{'(' if self.low_open else '['}{_number(self.low)}, {_number(self.high)}]"
        return f"{text} {self.unit}" if self.unit else text


def _number(value: float) -> str:
    return str(int(value)) if float(value).is_integer() else f"{value:g}"


FRICTION = Bounds(0, 10, "", "Coulomb coefficient; rubber on rough ground is about 1 to 2")
SERVO_DAMPING = Bounds(0, 10, "N·m·s/rad", "a desk servo's is 0.001 to 1")
ARMATURE = Bounds(0, 1, "kg·m²", "reflected rotor inertia; an XM430's is 0.045")
FRICTION_LOSS = Bounds(0, 10, "N·m", "dry friction at the joint; an XM430's is 0.03")
# One range for the P divisor, in the servo file and in a robot's [twin.servo] override alike.
P_GAIN_DIVISOR = Bounds(
    1, 1e6, "", "Position P Gain units per unit of duty per tick (256 on X series)"
)

ROBOT: dict[str, Bounds] = {
    "link.length_m": Bounds(0.01, 1.0, "m", "joint-to-joint pitch of one module"),
    "link.radius_m": Bounds(0.001, 0.25, "m", "capsule radius; also 2 × radius_m < length_m"),
    "link.mass_kg": Bounds(0.001, 20, "kg", "one module: servo, bracket and screws"),
    "safety.ramp_s": Bounds(0, 30, "s", "amplitude ramp at start and stop; 0 switches it off"),
    "safety.max_speed_fraction": Bounds(
        0, 1, "", "of the servo's no-load speed at the supply voltage", low_open=True
    ),
    "twin.timestep_s": Bounds(0.0001, 0.02, "s", "MuJoCo's step; 2 ms suits desk servos"),
    "twin.axial_friction": FRICTION,
    "twin.lateral_friction": FRICTION,
    "twin.backward_friction": FRICTION,
    "twin.servo.stiffness_scale": Bounds(0.01, 100, "", "sysid's factor on the servo stiffness"),
    "twin.servo.damping_nms": SERVO_DAMPING,
    "twin.servo.armature_kgm2": ARMATURE,
    "twin.servo.friction_loss_nm": FRICTION_LOSS,
    "twin.servo.actuator_delay_s": Bounds(
        0, MAX_ACTUATOR_DELAY_S, "s", "command to action; a Dynamixel chain's is a few ms"
    ),
    "twin.servo.p_gain_divisor": P_GAIN_DIVISOR,
    "joints[].servo_id": Bounds(0, 252, "", "Dynamixel IDs (253 and up are reserved)"),
    "joints[].zero_offset_rad": Bounds(-math.pi, math.pi, "rad", "calibration offset"),
    "joints[].lower_rad": Bounds(-math.pi, 0, "rad", "joint limit; also lower_rad < upper_rad"),
    "joints[].upper_rad": Bounds(0, math.pi, "rad", "joint limit"),
}
"""Robot-file keys (``joints[]`` also covers ``[joint_defaults]``) and their ranges."""

SERVO: dict[str, Bounds] = {
    "physics.supply_voltage_v": Bounds(1, 60, "V", "what the power supply gives"),
    "physics.armature_kgm2": ARMATURE,
    "physics.friction_loss_nm": FRICTION_LOSS,
    "physics.viscous_damping_nms": SERVO_DAMPING,
    "physics.pwm_limit": Bounds(
        1, 2009, "", "PWM full scale (885 on X series); at most the PWM Limit register's maximum"
    ),
    "physics.d_gain_loop_period_s": Bounds(1e-5, 0.1, "s", "the firmware's D-term period"),
    "physics.p_gain_divisor": P_GAIN_DIVISOR,
    "physics.d_gain_divisor": Bounds(
        1, 1e6, "", "Position D Gain units per unit of duty per tick per loop period (32)"
    ),
}
"""Servo-file (``servos/<model>.toml``) keys and their ranges."""

BODY: dict[str, Bounds] = {
    "lattice.segments": Bounds(1, 64, "", "cubes, head to tail"),
    "lattice.segment_length_m": Bounds(0.001, 1, "m", "the relaxed cube's side along the body"),
    "lattice.width_m": Bounds(0.001, 1, "m", "the relaxed cube's side across the body"),
    "lattice.height_m": Bounds(0.001, 1, "m", "the relaxed cube's height"),
    "lattice.point_mass_kg": Bounds(0.0001, 10, "kg", "each point; also Miller's mass unit"),
    "lattice.point_radius_m": Bounds(
        0.0001, 0.5, "m", "contact sphere; also 2 × point_radius_m < the shortest side"
    ),
    "springs.k": Bounds(0.001, 1000, "", "Miller's spring strength (0.3 to 1.5 in his table)"),
    "springs.damping": Bounds(0, 1000, "", "Miller's damping (0.6 to 3.5 in his table)"),
    "springs.time_unit_s": Bounds(0.001, 1, "s", "Miller's time unit T"),
    "muscles.max_bend_rad": Bounds(0, math.pi / 2, "rad", "yaw and pitch limit", low_open=True),
    "muscles.max_contraction": Bounds(0, 0.8, "", "axial strain, both ways", low_open=True),
    "muscles.max_rate_per_s": Bounds(0.01, 1000, "", "slew limit of every channel (rad/s, 1/s)"),
    "ground.friction": FRICTION,
    "safety.ramp_s": ROBOT["safety.ramp_s"],
    "twin.timestep_s": Bounds(
        0.00001, 0.005, "s", "physics step; also timestep_s · √(9k/m) < 1 (explicit springs)"
    ),
}
"""Mass-spring body-file (``bodies/<name>.toml``) keys and their ranges."""

JOINT_COUNT = (2, 64)
"""Fewest and most joints a robot may have (the twin's builder is checked over this range)."""
