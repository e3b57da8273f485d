"""Position P/D Gain registers <-> physical stiffness and damping, for one servo model.

A Dynamixel position loop is a voltage P(I)D controller (Rhoban/bam, ``bam/actuator.py``):
duty = clip(error_gain * P * err, ±1), torque = (kt/R) * (duty * V - kt * qdot). For small
errors that is a spring of stiffness K = tau_stall(V) * error_gain * P, with the error gain per
unit of P = (ticks/rad) / (p_gain_divisor * PWM Limit). X-series firmware computes KPP = P/128 on
an output out of 2 * PWM Limit, hence ``p_gain_divisor`` 256; KPD = D/16 per tick per loop
period, hence ``d_gain_divisor`` 32 (D weighs p_gain_divisor / d_gain_divisor = 8 P units, per
``d_gain_loop_period_s``). The divisors are per-servo numbers in the servo file (docs/twin.md);
256 is bam's fit of one XL330, so a robot file's ``[twin.servo]`` may override ``p_gain_divisor``
with what ``snakebot sysid --params p_divisor`` fits, and that robot's mapping uses it throughout.

Only the Dynamixel layer and the robot-file loader use the register side; the Backend contract
carries :class:`snakebot.types.PDGains` in SI.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from snakebot.types import PDGains


@dataclass(frozen=True)
class GainMapping:
    """The P and D registers' meaning in SI for one servo model at its supply voltage.

    ``stall_torque_nm`` is at the supply voltage; ``p_max``/``d_max`` are the control table's
    Position P/D Gain maxima. Registers -> SI is exact; SI -> registers rounds and clips.
    """

    stall_torque_nm: float
    ticks_per_rad: float
    pwm_limit: int
    p_gain_divisor: float
    d_gain_divisor: float
    d_gain_loop_period_s: float
    p_max: int
    d_max: int

    @property
    def error_gain(self) -> float:
        """Duty (fraction of full PWM) per radian of error per unit of the P register."""
        return self.ticks_per_rad / (self.p_gain_divisor * self.pwm_limit)

    def kp_nm_per_rad(self, position_p: float) -> float:
        """The stiffness (N·m/rad) a Position P Gain register value gives."""
        return self.stall_torque_nm * self.error_gain * position_p

    def kd_nms_per_rad(self, position_d: float) -> float:
        """The damping (N·m·s/rad) a Position D Gain register value gives."""
        weight = self.p_gain_divisor / self.d_gain_divisor
        return (
            self.stall_torque_nm * self.error_gain * weight * position_d * self.d_gain_loop_period_s
        )

    def pd_gains(self, position_p: int, position_d: int) -> PDGains:
        """SI gains of the P and D register values."""
        return PDGains(self.kp_nm_per_rad(position_p), self.kd_nms_per_rad(position_d))

    @property
    def max_gains(self) -> PDGains:
        """The stiffest and most damped gains the registers reach."""
        return self.pd_gains(self.p_max, self.d_max)

    def position_p(self, kp_nm_per_rad: float) -> int:
        """The nearest Position P Gain register value for a stiffness, clipped to 0..p_max."""
        return _register(kp_nm_per_rad / self.kp_nm_per_rad(1), self.p_max)

    def position_d(self, kd_nms_per_rad: float) -> int:
        """The nearest Position D Gain register value for a damping, clipped to 0..d_max."""
        return _register(kd_nms_per_rad / self.kd_nms_per_rad(1), self.d_max)

    def registers(self, gains: PDGains) -> tuple[int, int]:
        """(Position P, Position D) register values for SI gains, rounded and clipped."""
        return self.position_p(gains.kp_nm_per_rad), self.position_d(gains.kd_nms_per_rad)


def _register(value: float, maximum: int) -> int:
    if not math.isfinite(value):
        return maximum if value > 0 else 0
    return int(min(max(round(value), 0), maximum))


COMPLIANCE_SLOPES = (2, 4, 8, 16, 32, 64, 128)
"""The AX series' Compliance Slope levels: the firmware uses the highest power of two not above
the register value (e-Manual ax-12a.md: 7 steps, 2..254)."""


@dataclass(frozen=True)
class ComplianceMapping:
    """An AX-series Compliance Slope register's meaning in SI, for one model at its supply voltage.

    The AX position loop has no PID: the output torque rises from Punch at the Compliance Margin
    to the Torque Limit over Compliance Slope ticks of error (e-Manual "Compliance"). Read as a
    spring, that is K = torque_limit / (slope * rad_per_tick) N·m/rad with no damping register
    (the twin's joint damping and back-EMF give the damping). ``torque_limit_nm`` is the stall
    torque at the supply voltage times the Torque Limit fraction. SI -> register picks the nearest
    level of :data:`COMPLIANCE_SLOPES` (in log scale).
    """

    torque_limit_nm: float
    rad_per_tick: float

    def slope_level(self, value: int) -> int:
        """The slope the firmware uses for a register value (highest power of two <= value)."""
        return max(s for s in COMPLIANCE_SLOPES if s <= max(value, 2))

    def kp_nm_per_rad(self, slope: int) -> float:
        """The stiffness (N·m/rad) a Compliance Slope register value gives."""
        return self.torque_limit_nm / (self.slope_level(slope) * self.rad_per_tick)

    def pd_gains(self, slope: int) -> PDGains:
        """SI gains of a Compliance Slope (no damping register: kd 0)."""
        return PDGains(self.kp_nm_per_rad(slope), 0.0)

    @property
    def max_gains(self) -> PDGains:
        """The stiffest setting (the smallest slope)."""
        return self.pd_gains(COMPLIANCE_SLOPES[0])

    def slope(self, kp_nm_per_rad: float) -> int:
        """The Compliance Slope level nearest (in log scale) to a stiffness."""
        if not math.isfinite(kp_nm_per_rad) or kp_nm_per_rad <= 0:
            return COMPLIANCE_SLOPES[-1] if not kp_nm_per_rad > 0 else COMPLIANCE_SLOPES[0]
        wanted = self.torque_limit_nm / (kp_nm_per_rad * self.rad_per_tick)
        return min(COMPLIANCE_SLOPES, key=lambda s: abs(math.log(s / wanted)))
