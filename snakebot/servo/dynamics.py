"""A Dynamixel in position mode as MuJoCo sees it: stiffness, damping, torque limit, armature,
and the delay from a command leaving the controller to the servo acting on it.

A Dynamixel position loop is a voltage P(I)D controller (Rhoban/bam, ``bam/actuator.py``):
duty = clip(error_gain * P * err, ±1), torque = (kt/R) * (duty * V - kt * qdot) - friction.
For small errors that is a PD (the SI gains the Backend contract carries; snakebot.servo.gains
maps the registers to them), a torque clip at tau_stall(V), and back-EMF damping
tau_stall / omega_no_load (the torque-speed line), so the datasheet's stall torque and no-load
speed are both honoured. See docs/twin.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from snakebot.config.schema import MAX_ACTUATOR_DELAY_S, ServoPhysics
from snakebot.types import PDGains


@dataclass(frozen=True)
class ServoDynamics:
    """MuJoCo parameters for one joint: position actuator kp/kv, joint damping, limits, and the
    actuator delay (s; None: the actuator keeps no command history)."""

    stiffness_nm_per_rad: float
    gain_damping_nms: float
    back_emf_damping_nms: float
    torque_limit_nm: float
    no_load_speed_rad_s: float
    armature_kgm2: float
    friction_loss_nm: float
    delay_s: float | None = None

    @property
    def joint_damping_nms(self) -> float:
        """Damping outside the servo's voltage clip: back-EMF plus viscous gear friction."""
        return self.back_emf_damping_nms

    def actuator_kv(self, timestep_s: float) -> float:
        """Velocity gain of the position actuator, including the stable-PD look-ahead term.

        Stable PD (Tan, Liu & Turk 2011) applies -Kp (q + h qdot - q_goal) - Kd qdot: the
        look-ahead is an extra damping h*Kp, which MuJoCo's implicitfast integrator then treats
        implicitly (the (M + Kd h)^-1 half of SPD). That keeps high gains stable at h = 5 ms.
        """
        return self.gain_damping_nms + timestep_s * self.stiffness_nm_per_rad


def servo_dynamics(physics: ServoPhysics, gains: PDGains) -> ServoDynamics:
    """Derive the twin's joint parameters from datasheet physics and SI position gains.

    The stiffness is ``gains.kp_nm_per_rad`` times sysid's ``stiffness_scale`` (1 unless fitted),
    the gain damping ``gains.kd_nms_per_rad``. There is no I term: the twin's loop is PD
    (docs/twin.md says why).
    """
    voltage_ratio = physics.supply_voltage_v / physics.nominal_voltage_v
    stall_torque = physics.stall_torque_nm * voltage_ratio
    no_load_speed = physics.no_load_speed_rad_s * voltage_ratio
    stiffness = gains.kp_nm_per_rad * physics.stiffness_scale
    gain_damping = gains.kd_nms_per_rad
    back_emf = physics.stall_torque_nm / physics.no_load_speed_rad_s + physics.viscous_damping_nms
    if physics.damping_nms is not None:  # fitted by sysid ([twin.servo] in the robot file)
        back_emf = physics.damping_nms
    return ServoDynamics(
        stiffness_nm_per_rad=stiffness,
        gain_damping_nms=gain_damping,
        back_emf_damping_nms=back_emf,
        torque_limit_nm=stall_torque,
        no_load_speed_rad_s=no_load_speed,
        armature_kgm2=physics.armature_kgm2,
        friction_loss_nm=physics.friction_loss_nm,
        delay_s=physics.actuator_delay_s,
    )


def history_samples(timestep_s: float) -> int:
    """Command samples a delayed actuator keeps: enough for ``MAX_ACTUATOR_DELAY_S`` plus the
    older neighbour that linear interpolation needs. It depends on the timestep only, so twins
    with different delays share one layout (and one ``mujoco.batch``)."""
    return math.ceil(MAX_ACTUATOR_DELAY_S / timestep_s) + 2
