"""Robot and servo settings as frozen dataclasses; SI units and radians throughout."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from snakebot.config.servos.extras import NO_EXTRAS, ServoExtras
from snakebot.servo import ComplianceMapping, GainMapping, TickModel
from snakebot.types import PDGains, StopPolicy

Axis = Literal["yaw", "pitch"]
GroundModel = Literal["anisotropic", "isotropic"]
FrictionModelName = Literal["auto", "pairs", "scale"]
GainKind = Literal["pid", "compliance"]

PID_GAIN_KEYS = ("position_p_gain", "position_i_gain", "position_d_gain")
"""The registers of a "pid" model's position loop (X series, MX in either firmware)."""
COMPLIANCE_GAIN_KEYS = ("cw_compliance_slope", "ccw_compliance_slope")
"""The registers that set a "compliance" model's stiffness (AX series), one per direction."""

# Longest actuator delay a robot file may set: far above a Dynamixel chain's few milliseconds
# of bus transfer and servo loop, and it sizes the twin's command history (docs/twin.md).
MAX_ACTUATOR_DELAY_S = 0.1


@dataclass(frozen=True)
class ServoPhysics:
    """Electromechanical facts of one servo model (datasheet values, see the servo file).

    ``stall_torque_nm`` and ``no_load_speed_rad_s`` are at ``nominal_voltage_v``; the twin scales
    them to ``supply_voltage_v``. Those, ``ticks`` (how the position registers count) and the model
    number come from the control-table data; ``p_gain_divisor``/``d_gain_divisor`` (the Position P/D
    Gain registers' meaning, snakebot.servo.gains) and the rest from the servo file.
    ``stiffness_scale`` (the twin's factor on the SI stiffness), ``damping_nms`` (joint damping with
    torque on, replacing back-EMF + viscous) and ``actuator_delay_s`` (seconds from a command
    leaving the controller to the servo acting on it, 0 to ``MAX_ACTUATOR_DELAY_S``; None: no delay
    model) come from a robot's ``[twin.servo]`` (sysid), which may also override ``p_gain_divisor``
    (then the robot's register gains are converted with the overridden divisor, for the twin and the
    bus alike). ``extras`` (electrics, overload, encoder and IMU noise) come from the servo file's
    ``[twin]``, overridden by the robot's ``[twin.servo]``.
    """

    stall_torque_nm: float
    no_load_speed_rad_s: float
    nominal_voltage_v: float
    supply_voltage_v: float
    armature_kgm2: float
    friction_loss_nm: float
    viscous_damping_nms: float
    ticks: TickModel
    pwm_limit: int
    d_gain_loop_period_s: float
    p_gain_divisor: float
    d_gain_divisor: float
    stiffness_scale: float = 1.0
    damping_nms: float | None = None
    actuator_delay_s: float | None = None
    extras: ServoExtras = NO_EXTRAS


@dataclass(frozen=True)
class GainRegisters:
    """Position P/I/D Gain register values (servo units): the robot file's ``[gains]`` as users
    know them. Only the loader, the Dynamixel layer and the tools that write registers use them;
    the Backend contract carries SI :class:`snakebot.types.PDGains`."""

    position_p: int
    position_i: int = 0
    position_d: int = 0


@dataclass(frozen=True)
class ServoModel:
    """A servo model: its name, model number, physics and how its position loop is set.

    ``gain_kind`` (the control-table data's ``gains``) says which registers set the loop:
    "pid" models have Position P/I/D Gain (``default_gains``/``gain_max`` are their factory values
    and maxima); "compliance" models (AX) have CW/CCW Compliance Slope instead, whose factory
    value is ``default_slope``, and output at most ``torque_limit`` (Torque Limit as a fraction of
    full torque) at the end of the slope; their ``default_gains``/``gain_max`` are all 0.
    Everything outside the Dynamixel layer uses SI gains (:meth:`gains_from`, :meth:`gain_writes`).
    """

    name: str
    model_number: int
    physics: ServoPhysics
    default_gains: GainRegisters
    gain_max: GainRegisters
    source: Path
    gain_kind: GainKind = "pid"
    default_slope: int = 32
    torque_limit: float = 1.0

    @property
    def gain_keys(self) -> tuple[str, ...]:
        """The control-table keys of the registers that set the position loop, in write order."""
        return PID_GAIN_KEYS if self.gain_kind == "pid" else COMPLIANCE_GAIN_KEYS

    @property
    def gain_mapping(self) -> GainMapping:
        """Position P/D Gain registers <-> SI stiffness and damping at the supply voltage.

        ValueError for a compliance model (it has no P/D registers; see
        :attr:`compliance_mapping`).
        """
        if self.gain_kind != "pid":
            raise ValueError(f"{self.name} has no Position P/D Gain (its loop is compliance)")
        physics = self.physics
        return GainMapping(
            stall_torque_nm=physics.stall_torque_nm * self._voltage_ratio,
            ticks_per_rad=physics.ticks.ticks_per_rad,
            pwm_limit=physics.pwm_limit,
            p_gain_divisor=physics.p_gain_divisor,
            d_gain_divisor=physics.d_gain_divisor,
            d_gain_loop_period_s=physics.d_gain_loop_period_s,
            p_max=self.gain_max.position_p,
            d_max=self.gain_max.position_d,
        )

    @property
    def compliance_mapping(self) -> ComplianceMapping:
        """Compliance Slope register <-> SI stiffness at the supply voltage and Torque Limit."""
        physics = self.physics
        return ComplianceMapping(
            torque_limit_nm=physics.stall_torque_nm * self._voltage_ratio * self.torque_limit,
            rad_per_tick=1.0 / physics.ticks.ticks_per_rad,
        )

    @property
    def _voltage_ratio(self) -> float:
        return self.physics.supply_voltage_v / self.physics.nominal_voltage_v

    @property
    def max_gains(self) -> PDGains:
        """The stiffest and most damped SI gains the model's registers reach."""
        if self.gain_kind == "pid":
            return self.gain_mapping.max_gains
        return self.compliance_mapping.max_gains

    @property
    def factory_gains(self) -> PDGains:
        """The SI gains of the model's factory register values."""
        if self.gain_kind == "pid":
            return self.gains_of(self.default_gains)
        return self.compliance_mapping.pd_gains(self.default_slope)

    def gain_writes(self, gains: PDGains, *, position_i: int = 0) -> dict[str, int]:
        """The register values (key -> value, in :attr:`gain_keys` order) for SI gains.

        "pid": Position P/I/D Gain from the stiffness and damping (rounded, clipped to the
        maxima) plus ``position_i``; "compliance": the Compliance Slope level nearest the
        stiffness, both directions alike (the damping has no register and is left out).
        """
        if self.gain_kind == "pid":
            p, d = self.gain_mapping.registers(gains)
            return dict(zip(PID_GAIN_KEYS, (p, position_i, d), strict=True))
        slope = self.compliance_mapping.slope(gains.kp_nm_per_rad)
        return dict.fromkeys(COMPLIANCE_GAIN_KEYS, slope)

    def gains_from(self, values: Mapping[str, int]) -> PDGains:
        """The SI gains of register values keyed as :attr:`gain_keys` (missing keys: factory).

        "pid": from Position P and D Gain (the I gain has no SI counterpart); "compliance": the
        mean of the two directions' stiffnesses, no damping. KeyError for a key the model's loop
        does not have.
        """
        unknown = set(values) - set(self.gain_keys)
        if unknown:
            raise KeyError(f"{self.name}'s position loop has no register {sorted(unknown)[0]!r}")
        if self.gain_kind == "pid":
            factory = self.default_gains
            return self.gain_mapping.pd_gains(
                values.get("position_p_gain", factory.position_p),
                values.get("position_d_gain", factory.position_d),
            )
        mapping = self.compliance_mapping
        stiffness = [
            mapping.kp_nm_per_rad(values.get(k, self.default_slope)) for k in COMPLIANCE_GAIN_KEYS
        ]
        return PDGains(sum(stiffness) / len(stiffness), 0.0)

    def gains_of(self, registers: GainRegisters) -> PDGains:
        """SI gains of Position P/D Gain register values (the I gain has no SI counterpart)."""
        return self.gain_mapping.pd_gains(registers.position_p, registers.position_d)

    def registers_of(self, gains: PDGains, position_i: int = 0) -> GainRegisters:
        """Position P/I/D Gain values for SI gains (rounded, clipped to the maxima); a "pid"
        model's :meth:`gain_writes` as :class:`GainRegisters` (ValueError on a compliance one)."""
        p, d = self.gain_mapping.registers(gains)
        return GainRegisters(p, position_i, d)


@dataclass(frozen=True)
class BusConfig:
    """Where the hardware chain is: serial port, baud rate and protocol version."""

    port: str
    baud: int
    protocol: float


@dataclass(frozen=True)
class JointConfig:
    """One joint, counted from the head: its servo ID, bending axis, calibration and limits."""

    servo_id: int
    axis: Axis
    zero_offset_rad: float
    direction: int
    lower_rad: float
    upper_rad: float


@dataclass(frozen=True)
class LinkConfig:
    """Geometry of every module: joint-to-joint pitch, capsule radius, mass."""

    length_m: float
    radius_m: float
    mass_kg: float


@dataclass(frozen=True)
class SafetyConfig:
    """Envelope the safety layer enforces between gait and backend."""

    ramp_s: float
    max_speed_fraction: float
    stop_policy: StopPolicy


@dataclass(frozen=True)
class TwinConfig:
    """MuJoCo twin options: timestep and ground friction along/across each link.

    ``friction_model``: "pairs" (MuJoCo capsule-plane pairs), "scale" (directional friction
    computed from contact forces, any ground) or "auto" (pairs where the snake lies on the floor
    plane, scale elsewhere). ``backward_friction`` (scale model; None = ``axial_friction``) is
    the coefficient for sliding tail-first.
    """

    timestep_s: float
    ground: GroundModel
    axial_friction: float
    lateral_friction: float
    friction_model: FrictionModelName = "auto"
    backward_friction: float | None = None


@dataclass(frozen=True)
class RobotConfig:
    """A whole robot: the servo chain head to tail plus what the twin needs to mirror it."""

    name: str
    source: Path
    servo: ServoModel
    bus: BusConfig
    joints: tuple[JointConfig, ...]
    link: LinkConfig
    gains: PDGains
    safety: SafetyConfig
    twin: TwinConfig
    position_i_gain: int = 0
    """The Position I Gain register: a Dynamixel-only setting (the twin's loop is PD), written by
    the Dynamixel backend at connect and by ``config apply``; not part of the Backend contract."""

    @property
    def gain_registers(self) -> GainRegisters:
        """The Position P/I/D Gain registers for :attr:`gains` and :attr:`position_i_gain`
        (a "pid" servo's; all 0 on a compliance servo, which has none)."""
        if self.servo.gain_kind != "pid":
            return GainRegisters(0, 0, 0)
        return self.servo.registers_of(self.gains, self.position_i_gain)

    @property
    def gain_writes(self) -> dict[str, int]:
        """The position-loop registers (key -> value) every servo gets for :attr:`gains`."""
        return self.servo.gain_writes(self.gains, position_i=self.position_i_gain)

    @property
    def joint_count(self) -> int:
        """Number of joints (servos), N."""
        return len(self.joints)

    @property
    def link_count(self) -> int:
        """Number of rigid modules: one more than the joints."""
        return len(self.joints) + 1

    @property
    def body_length_m(self) -> float:
        """Head-to-tail length when straight."""
        return self.link_count * self.link.length_m

    @property
    def total_mass_kg(self) -> float:
        """Mass of all modules."""
        return self.link_count * self.link.mass_kg

    @property
    def servo_ids(self) -> tuple[int, ...]:
        """Servo IDs head to tail."""
        return tuple(j.servo_id for j in self.joints)

    @property
    def lower_rad(self) -> np.ndarray:
        """Lower joint limits, shape (N,)."""
        return np.array([j.lower_rad for j in self.joints])

    @property
    def upper_rad(self) -> np.ndarray:
        """Upper joint limits, shape (N,)."""
        return np.array([j.upper_rad for j in self.joints])

    @property
    def max_speed_rad_s(self) -> float:
        """Joint speed the safety layer allows: a fraction of the servo's no-load speed."""
        physics = self.servo.physics
        no_load = physics.no_load_speed_rad_s * physics.supply_voltage_v / physics.nominal_voltage_v
        return self.safety.max_speed_fraction * no_load
